//! The diffusion transformer of DiT-Garment (Sana-style, burn 0.22 on the `flex` CPU backend):
//! its configuration (`config.rs`), the block's pieces (`layers.rs`) and the network
//! (`dit.rs`), and its one hand-written kernel (`kernels.rs`). Training and sampling live apart
//! (`crate::train`, `crate::predict`).

mod config;
mod dit;
mod kernels;
mod layers;

pub use config::{
    BODY_CHANNELS, Depthwise, DitConfig, FREQUENCY_DIM, INPUT_CHANNELS, NEAREST_CHANNELS,
    OUTPUT_CHANNELS, Prediction,
};
pub use dit::{Block, ConditionEmbedder, Dit, TimestepEmbedder};
pub use layers::{CrossAttention, DepthwiseConv, LinearAttention, MixFfn, norm, timestep_features};

#[cfg(test)]
pub(crate) mod tests {
    /// A model small enough for tests: 32 x 32, patch 4, width 16, 2 blocks, 5 conditions.
    pub(crate) fn tiny() -> super::DitConfig {
        super::DitConfig {
            resolution: 32,
            patch: 4,
            width: 16,
            depth: 2,
            heads: 2,
            mlp_ratio: 2.0,
            condition_tokens: 2,
            condition_dim: 5,
            body_inputs: false,
            ..super::DitConfig::default()
        }
    }
}
