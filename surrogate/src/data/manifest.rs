//! `manifest.json` of a training tensors folder: its layout, counts, checksums and the
//! train split's normalization statistics, and the checks a loaded manifest must pass.

use std::collections::BTreeMap;

use dataset::MaterialRanges;
use serde::{Deserialize, Serialize};

use super::conditions::{Block, ConditionLayout, ConditionScaling};
use super::stats::Stats;
use crate::geometry::{RootRemoval, TargetKind};
use crate::model::{BODY_CHANNELS, NEAREST_CHANNELS};

/// One shard file.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct ShardInfo {
    /// File name in the tensors folder.
    pub file: String,
    /// Frames in it.
    pub frames: usize,
    /// SHA-256 of the file, hex.
    pub sha256: String,
}

/// Counts of one split.
#[derive(Debug, Clone, Default, PartialEq, Serialize, Deserialize)]
pub struct SplitInfo {
    /// Frames (samples).
    pub frames: usize,
    /// Sequences.
    pub sequences: usize,
    /// Of them, how many are also held mirrored (`--mirror`, train split only: each adds a
    /// second copy of its frames, the mirror image).
    #[serde(default, skip_serializing_if = "is_zero")]
    pub mirrored: usize,
    /// Shard files, in order.
    pub shards: Vec<ShardInfo>,
}

/// One template.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct TemplateInfo {
    /// Garment name (as in the dataset's manifest).
    pub name: String,
    /// Its index in `templates.safetensors` and `template_index`.
    pub index: usize,
    /// Vertices.
    pub vertices: usize,
    /// Inside texels over all texels.
    pub coverage: f64,
    /// Frames per split using it.
    pub frames: BTreeMap<String, usize>,
    /// With `--mirror`: the mean distance from its mirrored vertices to its surface, m; a
    /// template past `--mirror-max-gap-cm` is not mirrored.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub mirror_gap_m: Option<f64>,
}

fn is_zero(n: &usize) -> bool {
    *n == 0
}

impl TemplateInfo {
    /// Whether a model trained on these tensors has seen this template (it has frames in the
    /// train split; the tensors hold the held-out splits' templates too).
    pub fn in_training(&self) -> bool {
        self.frames.get("train").is_some_and(|&n| n > 0)
    }
}

/// Normalization statistics, computed on the train split only.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Normalization {
    /// Per target channel over the loss-mask texels of train frames.
    pub targets: Stats,
    /// Per condition dimension over train frames.
    pub conditions: Stats,
    /// Per channel of the position maps of the templates train frames use, over inside texels.
    pub position_maps: Stats,
    /// Per channel of the body inputs over the loss-mask texels of train frames (none where
    /// the tensors have no body inputs).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub bodies: Option<Stats>,
}

/// The format `dataset tensors` writes (`manifest.json`'s `format`).
pub const TENSORS_FORMAT: u32 = 2;
/// The smallest standard deviation statistics hold (constant channels get 1; see
/// `stats::stats`).
const MIN_STD: f64 = 1e-12;
/// The largest mean or deviation any of this project's data has, by far (metres, normalized
/// conditions and material values are all under 1e3).
const MAX_STATISTIC: f64 = 1e6;

/// `manifest.json` of a tensors folder.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct TensorManifest {
    /// Format version.
    pub format: u32,
    /// The dataset folder the tensors came from.
    pub source: String,
    /// Texels per side.
    pub resolution: usize,
    /// `displacement` or `lbs_residual`.
    pub target: TargetKind,
    /// Earlier frames in each pose window.
    pub window: usize,
    /// Motion frame stride.
    pub every: usize,
    /// Root rotation the canonical frame removes.
    pub root: RootRemoval,
    /// The condition layout (shape count, window, material ranges, scaling), stored once:
    /// prediction builds every condition vector from it. Absent in manifests written before
    /// 2026-12-04, whose layout [`TensorManifest::condition_layout`] infers.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub condition_layout: Option<ConditionLayout>,
    /// Condition vector blocks (what each holds, for readers; [`ConditionLayout::blocks`]).
    pub condition: Vec<Block>,
    /// Condition vector length.
    pub condition_dim: usize,
    /// Material normalization ranges (the dataset spec's).
    pub material_ranges: MaterialRanges,
    /// The body model the conditions and targets were made with.
    pub body_model: String,
    /// Per split: frames, sequences, shards.
    pub splits: BTreeMap<String, SplitInfo>,
    /// Held-out splits of the datasets whose sequences were trained on (`--train-splits`: a
    /// refit on training and validation data); empty otherwise.
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub joined_to_train: Vec<String>,
    /// The templates, in index order.
    pub templates: Vec<TemplateInfo>,
    /// `templates.safetensors` checksum.
    pub templates_sha256: String,
    /// Normalization statistics (train split).
    pub normalization: Normalization,
}

impl TensorManifest {
    /// Whether the normalization statistics have the lengths the layout asks for (a hand-edited
    /// or foreign manifest may not).
    pub fn normalization_fits(&self) -> bool {
        let n = &self.normalization;
        [&n.targets, &n.position_maps]
            .iter()
            .all(|s| s.mean.len() == 3 && s.std.len() == 3)
            && n.conditions.mean.len() == self.condition_dim
            && n.conditions.std.len() == self.condition_dim
            && n.bodies.as_ref().is_none_or(|s| {
                [BODY_CHANNELS, BODY_CHANNELS + NEAREST_CHANNELS].contains(&s.mean.len())
                    && s.std.len() == s.mean.len()
            })
    }

    /// What is wrong with the manifest's numbers, if anything: an unknown format, a mean or
    /// standard deviation that is not finite, a deviation not positive or beyond any data's,
    /// a material range that is empty. Sampling divides and multiplies by these, so such a
    /// manifest would give non-finite or silently wrong cloth; it is refused at load.
    pub fn statistics_problem(&self) -> Option<String> {
        if !(1..=TENSORS_FORMAT).contains(&self.format) {
            return Some(format!(
                "format {} (this build reads 1 to {TENSORS_FORMAT})",
                self.format
            ));
        }
        if let Some(layout) = &self.condition_layout {
            // Bounded before the layout's size is computed, which would overflow.
            if layout.window > 64 {
                return Some(format!(
                    "condition_layout.window is {} (at most 64 earlier frames)",
                    layout.window
                ));
            }
            if layout.betas > 300 {
                return Some(format!(
                    "condition_layout.betas is {} (at most 300 shape values)",
                    layout.betas
                ));
            }
            if layout.dim() != self.condition_dim {
                return Some(format!(
                    "condition_layout makes {} values, condition_dim says {}",
                    layout.dim(),
                    self.condition_dim
                ));
            }
        }
        let n = &self.normalization;
        let named = [
            ("targets", Some(&n.targets)),
            ("conditions", Some(&n.conditions)),
            ("position_maps", Some(&n.position_maps)),
            ("bodies", n.bodies.as_ref()),
        ];
        for (name, stats) in named {
            let Some(stats) = stats else { continue };
            if let Some((c, m)) = stats
                .mean
                .iter()
                .enumerate()
                .find(|(_, m)| !(m.is_finite() && m.abs() <= MAX_STATISTIC))
            {
                return Some(format!(
                    "normalization.{name}.mean[{c}] is {m} (finite, at most {MAX_STATISTIC:e} in size)"
                ));
            }
            if let Some((c, s)) = stats
                .std
                .iter()
                .enumerate()
                .find(|(_, s)| !(s.is_finite() && (MIN_STD..=MAX_STATISTIC).contains(*s)))
            {
                return Some(format!(
                    "normalization.{name}.std[{c}] is {s} ({MIN_STD:e} to {MAX_STATISTIC:e})"
                ));
            }
        }
        let r = &self.material_ranges;
        for (name, [low, high]) in [("k_s", r.k_s), ("rho", r.rho), ("log10_k_b", r.log10_k_b)] {
            if !(low.is_finite() && high.is_finite() && low < high) {
                return Some(format!(
                    "material_ranges.{name} is [{low}, {high}] (an increasing pair of finite values)"
                ));
            }
        }
        None
    }

    /// Channels of the shards' body inputs: 0, [`BODY_CHANNELS`], or with the nearest body
    /// points [`BODY_CHANNELS`] + [`NEAREST_CHANNELS`].
    pub fn body_channels(&self) -> usize {
        self.normalization
            .bodies
            .as_ref()
            .map_or(0, |s| s.mean.len())
    }

    /// The condition layout the manifest records; for a manifest written before it was
    /// stored, the one its blocks, window and material ranges describe on a body model with
    /// `betas` shape coefficients.
    pub fn condition_layout(&self, betas: usize) -> ConditionLayout {
        if let Some(layout) = self.condition_layout {
            return layout;
        }
        let bounded = self
            .condition
            .iter()
            .any(|b| b.name == super::conditions::VELOCITIES);
        ConditionLayout {
            betas,
            window: self.window,
            material: self.material_ranges,
            scaling: if bounded {
                ConditionScaling::Bounded
            } else {
                ConditionScaling::ZScore
            },
        }
    }
}
