//! The model's configuration: one plain struct, saved as TOML beside every checkpoint and
//! checked on load, so weights are never read into a network of another shape.

use serde::{Deserialize, Serialize};

use crate::error::{Result, bad_value};
use crate::geometry::TargetKind;

/// Channels of the network's input image without body inputs: noisy target (3), position map
/// (3), mask (1).
pub const INPUT_CHANNELS: usize = 7;
/// Channels the body inputs add: the skinned base (canonical, 3) and its change since the
/// previous frame (3).
pub const BODY_CHANNELS: usize = 6;
/// Channels the nearest-body inputs add to the body inputs: the offset from the skinned
/// template to the nearest point of the posed body (canonical, 3) and that point's outward
/// normal (3).
pub const NEAREST_CHANNELS: usize = 6;
/// Channels the previous-state input adds: the garment's target map at the previous frame
/// (the simulated one, noised, in training; the model's own output when predicting).
pub const PREVIOUS_CHANNELS: usize = 3;
/// Channels of its output: the velocity of the target map, or the map itself.
pub const OUTPUT_CHANNELS: usize = 3;
/// Width of the sinusoidal timestep features (Sana's and DiT's 256).
pub const FREQUENCY_DIM: usize = 256;

/// How the Mix-FFN's 3 x 3 depthwise convolution is computed in training, where gradients
/// flow (same function, two speeds; the brief warned that burn's grouped `Conv2d` backward
/// runs one small convolution per channel on the CPU, but at these sizes it measured faster
/// than the shifted form). Sampling ignores it: without gradients the Mix-FFN's middle always
/// runs as one vectorized kernel (`MixFfn::sampling_middle`, docs/SURROGATE_ARMS.md "A faster
/// network call"), tested equal to both forms.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum Depthwise {
    /// Nine shifted multiply-adds over the padded token grid.
    Shifted,
    /// burn's `Conv2d` with one group per channel.
    Conv2d,
}

/// What the network's output means. Either way the sampler integrates the same flow; only
/// what the network has to produce differs.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
pub enum Prediction {
    /// The velocity eps - z0 (rectified flow's usual output; what a configuration without the
    /// key means, so runs made before the key existed load unchanged).
    #[serde(rename = "velocity")]
    Velocity,
    /// The clean target map z0; the sampler's velocity is (x - z0_hat) / s. The output never
    /// has to reproduce the input noise texel by texel, which a small network does only
    /// roughly (the velocity model's garments came out crumpled: docs/SURROGATE.md).
    #[serde(rename = "x0")]
    Data,
}

impl Prediction {
    fn before_the_key() -> Self {
        Prediction::Velocity
    }
}

/// A Sana-style DiT over UV geometry images (docs/SURROGATE.md, "The model").
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct DitConfig {
    /// Texels per side of the geometry images (32, 64 or 128).
    pub resolution: usize,
    /// Texels per side of one token (1, 2 or 4).
    pub patch: usize,
    /// Token width C.
    pub width: usize,
    /// Transformer blocks.
    pub depth: usize,
    /// Attention heads (self- and cross-attention); `width` must divide by it.
    pub heads: usize,
    /// Mix-FFN hidden width over `width`.
    pub mlp_ratio: f64,
    /// Condition tokens the condition MLP makes for cross-attention.
    pub condition_tokens: usize,
    /// Length of the condition vector (the training tensors' `condition_dim`).
    pub condition_dim: usize,
    /// What the target maps hold (the training tensors' `target`).
    pub target: TargetKind,
    /// How the depthwise convolution is computed.
    pub depthwise: Depthwise,
    /// What the output is (`velocity` or `x0`).
    #[serde(default = "Prediction::before_the_key")]
    pub prediction: Prediction,
    /// Whether every texel also sees the body: the template skinned to the frame's body
    /// (canonical frame) and its change since the previous frame, 6 more input channels (a
    /// saved configuration without the key has none).
    #[serde(default)]
    pub body_inputs: bool,
    /// Whether the body inputs also hold, per texel, the offset to the nearest point of the
    /// posed body and its normal, 6 more channels (needs `body_inputs`; a saved configuration
    /// without the key has none).
    #[serde(default)]
    pub body_nearest: bool,
    /// Whether every texel also sees the garment's previous state, 3 more input channels: an
    /// autoregressive mode the paper does not have, for cloth whose swing the pose window
    /// does not tell (docs/SURROGATE.md, "The autoregressive mode"). A model with it predicts
    /// the frames of a sequence one after another.
    #[serde(default)]
    pub previous_state: bool,
}

impl Default for DitConfig {
    fn default() -> Self {
        Self {
            resolution: 64,
            // Patch 4 on this CPU: 4x the training samples/s of patch 2 and 3.5x faster
            // forwards (docs/BENCHMARKS.md), while 64 x 64 keeps the UV floor at 0.02-0.14 cm.
            patch: 4,
            width: 128,
            depth: 4,
            heads: 4,
            mlp_ratio: 2.5,
            condition_tokens: 8,
            condition_dim: 415,
            target: TargetKind::LbsResidual,
            // Measured faster than the shifted multiply-adds in training (12.0 vs 10.1
            // samples/s at patch 4, 2.6 vs 1.8 at patch 2; docs/BENCHMARKS.md).
            depthwise: Depthwise::Conv2d,
            prediction: Prediction::Data,
            body_inputs: true,
            body_nearest: false,
            previous_state: false,
        }
    }
}

impl DitConfig {
    /// Names the first bad value (`key = value: what is expected`).
    pub fn validate(&self) -> Result<()> {
        let bad = |key: &str, value: &dyn std::fmt::Display, expected: &str| {
            Err(bad_value(&format!("model.{key}"), value, expected))
        };
        if ![32, 64, 128].contains(&self.resolution) {
            return bad("resolution", &self.resolution, "must be 32, 64 or 128");
        }
        if ![1, 2, 4].contains(&self.patch) {
            return bad("patch", &self.patch, "must be 1, 2 or 4");
        }
        if self.width == 0 || self.width > 4096 {
            return bad("width", &self.width, "must be 1 to 4096");
        }
        if self.depth == 0 || self.depth > 64 {
            return bad("depth", &self.depth, "must be 1 to 64");
        }
        if self.heads == 0 || !self.width.is_multiple_of(self.heads) {
            return bad("heads", &self.heads, "must divide the width");
        }
        if !(self.mlp_ratio.is_finite() && self.mlp_ratio > 0.0 && self.mlp_ratio <= 16.0) {
            return bad("mlp_ratio", &self.mlp_ratio, "must be in (0, 16]");
        }
        if self.condition_tokens == 0 || self.condition_tokens > 256 {
            return bad(
                "condition_tokens",
                &self.condition_tokens,
                "must be 1 to 256",
            );
        }
        if self.condition_dim == 0 || self.condition_dim > 1 << 16 {
            return bad("condition_dim", &self.condition_dim, "must be 1 to 65536");
        }
        let parameters = self.parameter_count();
        if parameters > MAX_PARAMETERS {
            return bad(
                "width",
                &self.width,
                &format!(
                    "with depth {}, mlp_ratio {} and {} condition tokens it makes {parameters} \
                     parameters; at most {MAX_PARAMETERS} (checked before any allocation)",
                    self.depth, self.mlp_ratio, self.condition_tokens
                ),
            );
        }
        if self.body_nearest && !self.body_inputs {
            return bad(
                "body_nearest",
                &self.body_nearest,
                "needs model.body_inputs = true (the nearest-body channels extend them)",
            );
        }
        Ok(())
    }

    /// Channels of the body inputs the model takes: 0, [`BODY_CHANNELS`], or those and
    /// [`NEAREST_CHANNELS`].
    pub fn body_channels(&self) -> usize {
        match (self.body_inputs, self.body_nearest) {
            (false, _) => 0,
            (true, false) => BODY_CHANNELS,
            (true, true) => BODY_CHANNELS + NEAREST_CHANNELS,
        }
    }

    /// Channels of the previous-state input: 0 or [`PREVIOUS_CHANNELS`].
    pub fn previous_channels(&self) -> usize {
        if self.previous_state {
            PREVIOUS_CHANNELS
        } else {
            0
        }
    }

    /// Channels of the input image: noisy target, position map (plus the body inputs and the
    /// previous state), mask.
    pub fn input_channels(&self) -> usize {
        INPUT_CHANNELS + self.body_channels() + self.previous_channels()
    }

    /// Channels of the per-texel inputs that come with the template, the body and the
    /// garment's past: the position map, then the body inputs and the previous state when the
    /// model takes them.
    pub fn texel_channels(&self) -> usize {
        self.input_channels() - 4
    }

    /// Tokens per side of the token grid.
    pub fn grid(&self) -> usize {
        self.resolution / self.patch
    }

    /// Mix-FFN hidden width H (the depthwise convolution runs over 2H channels).
    pub fn hidden(&self) -> usize {
        ((self.width as f64 * self.mlp_ratio).round() as usize).max(1)
    }

    /// The network's parameter count, from the configuration alone (what [`super::Dit::new`]
    /// would allocate; tested equal to the built network's count).
    pub fn parameter_count(&self) -> usize {
        let linear = |i: usize, o: usize| i * o + o;
        let (c, h, p2) = (self.width, self.hidden(), self.patch * self.patch);
        let block = 6 * c
            + 3 * c * c
            + linear(c, c)
            + linear(c, c)
            + linear(c, 2 * c)
            + linear(c, c)
            + linear(c, 2 * h)
            + 2 * h * 10
            + linear(h, c);
        linear(self.input_channels() * p2, c)
            + linear(FREQUENCY_DIM, c)
            + linear(c, c)
            + linear(c, 6 * c)
            + linear(self.condition_dim, c)
            + linear(c, self.condition_tokens * c)
            + self.depth * block
            + 2 * c
            + linear(c, OUTPUT_CHANNELS * p2)
    }

    /// Bytes one training sample's activations take, estimated high: every block keeps about
    /// a dozen token-wide and eight hidden-wide tensors for the backward pass, and the input
    /// and target images a few copies each.
    pub fn activation_bytes_per_sample(&self) -> usize {
        let tokens = self.grid() * self.grid();
        let texels = self.resolution * self.resolution;
        let per_block = tokens * (12 * self.width + 8 * self.hidden());
        4 * (self.depth * per_block + 8 * texels * (self.input_channels() + OUTPUT_CHANNELS))
    }
}

/// The most parameters a network may have here: 100 M (400 MB of f32, about 1.6 GB with the
/// optimizer's moments and the gradients); the shipped network has 1.4 M.
pub const MAX_PARAMETERS: usize = 100_000_000;

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn bad_values_are_named() {
        let mut c = DitConfig::default();
        assert!(c.validate().is_ok());
        c.heads = 3;
        assert_eq!(
            c.validate().unwrap_err().to_string(),
            "model.heads = 3: must divide the width"
        );
        c = DitConfig {
            patch: 3,
            ..DitConfig::default()
        };
        assert!(
            c.validate()
                .unwrap_err()
                .to_string()
                .starts_with("model.patch = 3")
        );
        c = DitConfig {
            body_inputs: false,
            body_nearest: true,
            ..DitConfig::default()
        };
        assert!(
            c.validate()
                .unwrap_err()
                .to_string()
                .starts_with("model.body_nearest")
        );
        c.body_inputs = true;
        assert_eq!(c.input_channels(), INPUT_CHANNELS + 12);
        c.previous_state = true;
        assert_eq!(c.input_channels(), INPUT_CHANNELS + 15);
        assert_eq!(c.texel_channels(), 3 + 12 + 3);
    }
}
