//! The diffusion transformer of DiT-Garment (Sana-style, burn 0.22 on the `flex` CPU backend):
//! its configuration (`config.rs`), the block's pieces (`layers.rs`) and the network
//! (`dit.rs`). Training and sampling live apart (`crate::train`, later `predict`).

mod config;
mod dit;
mod layers;

pub use config::{Depthwise, DitConfig, FREQUENCY_DIM, INPUT_CHANNELS, OUTPUT_CHANNELS};
pub use dit::{Block, ConditionEmbedder, Dit, TimestepEmbedder};
pub use layers::{CrossAttention, DepthwiseConv, LinearAttention, MixFfn, norm, timestep_features};
