//! The condition vector of one frame: body shape, pose window and material, in a documented
//! layout (names, offsets, sizes) that the tensors' manifest records.
//!
//! | name | size | content |
//! |---|---|---|
//! | `betas` | B (the body model's, 10 for the default body) | shape coefficients as recorded |
//! | `rotations_6d` | (L + 1) x 22 x 6 | the window's joint rotations (body joints, hands dropped), oldest frame first, each as the first two columns of its rotation matrix; root orientations with the current frame's heading removed (`Motion::pose_window`) |
//! | `translations` | L x 3 | the L earlier frames' root translations relative to the current frame's, in its heading frame, m |
//! | `material` | 3 | k_s, rho and log10 k_b, each mapped linearly from the dataset's range to [-1, 1] |
//! | `velocities_6d` | 22 x 6 | (bounded and history scalings) the current frame's 6D rotations minus the previous frame's, per second |
//! | `history_<ms>ms_rotations`, `history_<ms>ms_translation` | 22 x 6, 3 | (history scaling only) per time constant of [`HISTORY_SECONDS`], the body's exponentially weighted past minus its present ([`pose_history`]) |
//!
//! How each block is scaled for the network is recorded with it ([`BlockScaling`]): with the
//! `bounded` layout the 6D rotations are left as they are (they are bounded, and dividing a
//! nearly constant spine component by its training std sent held-out motions to -164 std),
//! the velocities share one scale, and the other blocks are z-scored with a floor under each
//! std.

use dataset::MaterialRanges;
use motions::Motion;
use motions::rotation::axis_angle_to_matrix;
use serde::{Deserialize, Serialize};
use sim::Material;

use super::history::{HISTORY_SECONDS, HISTORY_VALUES, pose_history};
use super::stats::Stats;
use crate::error::Result;

/// Joint `j`'s rotation in `pose` (axis-angle, 3 values a joint) as its 6D form: the first two
/// columns of its rotation matrix, column by column.
pub(crate) fn joint_6d(pose: &[f64], j: usize) -> [f64; 6] {
    let m = axis_angle_to_matrix([pose[3 * j], pose[3 * j + 1], pose[3 * j + 2]]);
    [
        m[(0, 0)],
        m[(1, 0)],
        m[(2, 0)],
        m[(0, 1)],
        m[(1, 1)],
        m[(2, 1)],
    ]
}

/// Joints whose rotations enter the condition: SMPL's 22 body joints (the hands are dropped:
/// the built-in motions and AMASS imports leave them at rest).
pub const CONDITION_JOINTS: usize = 22;

/// How a block of the condition vector is scaled before the network sees it.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum BlockScaling {
    /// Each value minus its training mean over its training std (1 where constant).
    #[default]
    ZScore,
    /// Each value minus its training mean over its training std, the std floored at a
    /// quarter of the block's pooled std (a value that hardly varies in training is not
    /// blown up where it does vary).
    ZScoreFloored,
    /// Left as it is (mean 0, std 1).
    None,
    /// Divided by the block's root mean square over training (one scale for the block,
    /// mean 0).
    Pooled,
}

/// One named block of the condition vector.
#[derive(Debug, Clone, PartialEq, Eq, Serialize, Deserialize)]
pub struct Block {
    /// Name.
    pub name: String,
    /// First index.
    pub offset: usize,
    /// Length.
    pub size: usize,
    /// How its values are scaled for the network (manifests written before the key:
    /// `z_score`).
    #[serde(default)]
    pub scaling: BlockScaling,
    /// What it holds, in words, with units.
    #[serde(default)]
    pub content: String,
}

/// Which condition layout and scaling a dataset's tensors use.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum ConditionScaling {
    /// Every value z-scored; no velocity block (the layout before issue 39).
    #[default]
    ZScore,
    /// 6D rotations unscaled, a velocity block with one scale, the rest z-scored with a
    /// std floor.
    Bounded,
    /// `Bounded`, then the body's longer past: one block per time constant of
    /// [`HISTORY_SECONDS`] (issue 53's longer velocity history).
    History,
}

impl ConditionScaling {
    /// The name used by flags and files.
    pub fn name(self) -> &'static str {
        match self {
            Self::ZScore => "zscore",
            Self::Bounded => "bounded",
            Self::History => "history",
        }
    }

    /// Parses a flag value.
    pub fn parse(text: &str) -> Option<Self> {
        match text {
            "zscore" => Some(Self::ZScore),
            "bounded" => Some(Self::Bounded),
            "history" => Some(Self::History),
            _ => None,
        }
    }
}

/// Maps `x` from `[lo, hi]` to [-1, 1] (0 for an empty range).
fn to_unit(x: f64, [lo, hi]: [f64; 2]) -> f64 {
    if hi > lo {
        2.0 * (x - lo) / (hi - lo) - 1.0
    } else {
        0.0
    }
}

/// The layout of condition vectors: the body's shape count and the window length.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct ConditionLayout {
    /// Shape coefficients.
    pub betas: usize,
    /// Earlier frames in the window (the window holds these and the current frame).
    pub window: usize,
    /// Material normalization.
    pub material: MaterialRanges,
    /// Layout and scaling (with `bounded`, a velocity block follows the material; with
    /// `history`, the history blocks follow that).
    #[serde(default)]
    pub scaling: ConditionScaling,
}

/// The name of the velocity block.
pub const VELOCITIES: &str = "velocities_6d";

impl ConditionLayout {
    /// The named blocks, in order.
    pub fn blocks(&self) -> Vec<Block> {
        let bounded = self.scaling != ConditionScaling::ZScore;
        let pick = |new: BlockScaling| {
            if bounded { new } else { BlockScaling::ZScore }
        };
        let mut sizes: Vec<(String, usize, BlockScaling, String)> = [
            (
                "betas",
                self.betas,
                pick(BlockScaling::ZScoreFloored),
                "shape coefficients of the frame",
            ),
            (
                "rotations_6d",
                (self.window + 1) * CONDITION_JOINTS * 6,
                pick(BlockScaling::None),
                "the window's 22 body-joint rotations, oldest frame first, first two matrix columns; root heading of the current frame removed",
            ),
            (
                "translations",
                self.window * 3,
                pick(BlockScaling::ZScoreFloored),
                "earlier frames' root translations relative to the current frame, heading frame, m",
            ),
            (
                "material",
                3,
                pick(BlockScaling::ZScoreFloored),
                "k_s, rho, log10 k_b mapped linearly from the dataset's ranges to [-1, 1]",
            ),
        ]
        .into_iter()
        .map(|(name, size, scaling, content)| (name.into(), size, scaling, content.into()))
        .collect();
        if bounded {
            sizes.push((
                VELOCITIES.into(),
                CONDITION_JOINTS * 6,
                BlockScaling::Pooled,
                "current minus previous frame's 6D rotations, per second".into(),
            ));
        }
        if self.scaling == ConditionScaling::History {
            // Rotations share one scale; the root's lag in metres is scaled apart (it
            // reaches a metre over a second of walking, far beyond any rotation's).
            for tau in HISTORY_SECONDS {
                let name = format!("history_{:.0}ms", tau * 1000.0);
                let past = format!(
                    "weighted over the past with time constant {tau} s, minus the current frame's"
                );
                sizes.push((
                    format!("{name}_rotations"),
                    HISTORY_VALUES - 3,
                    BlockScaling::Pooled,
                    format!("the 22 joints' 6D rotations {past}; root in the heading frame"),
                ));
                sizes.push((
                    format!("{name}_translation"),
                    3,
                    BlockScaling::ZScoreFloored,
                    format!("the root translation {past}; heading frame, m"),
                ));
            }
        }
        let mut offset = 0;
        sizes
            .into_iter()
            .map(|(name, size, scaling, content)| {
                let block = Block {
                    name,
                    offset,
                    size,
                    scaling,
                    content,
                };
                offset += size;
                block
            })
            .collect()
    }

    /// The scaling statistics of condition vectors from their per-value sums and sums of
    /// squares over `count` training frames, block by block as [`Block::scaling`] says.
    pub fn statistics(&self, sum: &[f64], sum2: &[f64], count: f64) -> Stats {
        let n = count.max(1.0);
        let (mut mean, mut std) = (vec![0.0; sum.len()], vec![1.0; sum.len()]);
        for block in self.blocks() {
            let range = block.offset..block.offset + block.size;
            let var = |d: usize| (sum2[d] / n - (sum[d] / n).powi(2)).max(0.0);
            let pooled_var = range.clone().map(var).sum::<f64>() / block.size.max(1) as f64;
            for d in range.clone() {
                match block.scaling {
                    BlockScaling::None => {}
                    BlockScaling::ZScore => {
                        mean[d] = sum[d] / n;
                        std[d] = if var(d) > 1e-24 { var(d).sqrt() } else { 1.0 };
                    }
                    BlockScaling::ZScoreFloored => {
                        mean[d] = sum[d] / n;
                        let floor = 0.25 * pooled_var.sqrt();
                        let s = var(d).sqrt().max(floor);
                        std[d] = if s > 1e-12 { s } else { 1.0 };
                    }
                    BlockScaling::Pooled => {
                        let rms = (range.clone().map(|d| sum2[d] / n).sum::<f64>()
                            / block.size.max(1) as f64)
                            .sqrt();
                        std[d] = if rms > 1e-12 { rms } else { 1.0 };
                    }
                }
            }
        }
        Stats { mean, std }
    }

    /// Length of a condition vector.
    pub fn dim(&self) -> usize {
        self.blocks().iter().map(|b| b.size).sum()
    }

    /// The condition vector of frame `t` of `motion` (the frames the body followed) with shape
    /// `betas` (padded with zeros or cut to the layout's count) and `material`.
    pub fn vector(
        &self,
        motion: &Motion,
        t: usize,
        betas: &[f64],
        material: &Material,
    ) -> Result<Vec<f64>> {
        let window = motion.pose_window(t, self.window)?;
        let mut out = Vec::with_capacity(self.dim());
        out.extend((0..self.betas).map(|i| betas.get(i).copied().unwrap_or(0.0)));
        for pose in &window.poses {
            for j in 0..CONDITION_JOINTS {
                out.extend(joint_6d(pose, j));
            }
        }
        for t in &window.transl[..self.window] {
            out.extend(t);
        }
        let m = self.material;
        out.push(to_unit(material.stretch, m.k_s));
        out.push(to_unit(material.density, m.rho));
        out.push(to_unit(material.bending.log10(), m.log10_k_b));
        if self.scaling != ConditionScaling::ZScore {
            // Within the current frame's heading frame, so the root's turning rate is kept.
            let (now, before) = (
                &window.poses[self.window],
                &window.poses[self.window.max(1) - 1],
            );
            for j in 0..CONDITION_JOINTS {
                let (a, b) = (joint_6d(now, j), joint_6d(before, j));
                out.extend((0..6).map(|i| (a[i] - b[i]) * motion.fps));
            }
        }
        if self.scaling == ConditionScaling::History {
            out.extend(pose_history(motion, t)?);
        }
        Ok(out)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use motions::{FramePose, POSE_DIM};

    #[test]
    fn a_known_pose_window_gives_hand_computed_values() {
        // Three frames walking along +x while facing +z; frame 2 has the left knee bent 90
        // degrees about x.
        let frame = |x: f64, knee: f64| {
            let mut pose = [0.0; POSE_DIM];
            pose[3 * 4] = knee;
            FramePose {
                pose,
                transl: [x, 0.9, 0.0],
            }
        };
        let half_pi = std::f64::consts::FRAC_PI_2;
        let frames = vec![frame(0.0, 0.0), frame(0.1, 0.0), frame(0.3, half_pi)];
        let motion = Motion::new("test", 30.0, frames).unwrap();
        let layout = ConditionLayout {
            betas: 10,
            window: 2,
            material: MaterialRanges::default(),
            scaling: ConditionScaling::ZScore,
        };
        let material = Material {
            stretch: 120.0,
            density: 0.01,
            bending: 1e-4,
        };
        let v = layout.vector(&motion, 2, &[0.5, -1.0], &material).unwrap();
        assert_eq!(v.len(), layout.dim());
        assert_eq!(layout.dim(), 10 + 3 * 22 * 6 + 6 + 3);
        assert_eq!(&v[..3], &[0.5, -1.0, 0.0]);
        let blocks = layout.blocks();
        let rot = blocks[1].offset;
        // Identity rotations: columns (1, 0, 0) and (0, 1, 0).
        assert_eq!(&v[rot..rot + 6], &[1.0, 0.0, 0.0, 0.0, 1.0, 0.0]);
        // The current frame's left knee, Rx(90): first column (1, 0, 0), second (0, 0, 1).
        let knee = rot + 2 * 22 * 6 + 4 * 6;
        let expected = [1.0, 0.0, 0.0, 0.0, 0.0, 1.0];
        for (a, b) in v[knee..knee + 6].iter().zip(expected) {
            assert!((a - b).abs() < 1e-12, "{:?}", &v[knee..knee + 6]);
        }
        // Translations of frames 0 and 1 relative to frame 2: (-0.3, 0, 0) and (-0.2, 0, 0).
        let tr = blocks[2].offset;
        let expected = [-0.3, 0.0, 0.0, -0.2, 0.0, 0.0];
        for (a, b) in v[tr..tr + 6].iter().zip(expected) {
            assert!((a - b).abs() < 1e-12, "{:?}", &v[tr..tr + 6]);
        }
        // Material: k_s 120 is the middle of [40, 200]; rho at the bottom; k_b at the top.
        let m = &v[blocks[3].offset..];
        assert!((m[0] - 0.0).abs() < 1e-12 && (m[1] + 1.0).abs() < 1e-12);
        assert!((m[2] - 1.0).abs() < 1e-12, "{m:?}");
    }

    #[test]
    fn the_bounded_layout_adds_velocities_and_scales_block_by_block() {
        let frame = |knee: f64| {
            let mut pose = [0.0; POSE_DIM];
            pose[3 * 4] = knee;
            FramePose {
                pose,
                transl: [0.0, 0.9, 0.0],
            }
        };
        let half_pi = std::f64::consts::FRAC_PI_2;
        let motion =
            Motion::new("test", 30.0, vec![frame(0.0), frame(0.0), frame(half_pi)]).unwrap();
        let layout = ConditionLayout {
            betas: 10,
            window: 2,
            material: MaterialRanges::default(),
            scaling: ConditionScaling::Bounded,
        };
        assert_eq!(layout.dim(), 415 + 22 * 6);
        let blocks = layout.blocks();
        let velocities = blocks.iter().find(|b| b.name == VELOCITIES).unwrap();
        let material = Material {
            stretch: 120.0,
            density: 0.01,
            bending: 1e-4,
        };
        let v = layout.vector(&motion, 2, &[], &material).unwrap();
        // The left knee turned by 90 degrees in one frame at 30 fps: second column
        // (0, 0, 1) - (0, 1, 0), per second.
        let knee = velocities.offset + 4 * 6;
        let expected = [0.0, 0.0, 0.0, 0.0, -30.0, 30.0];
        for (a, b) in v[knee..knee + 6].iter().zip(expected) {
            assert!((a - b).abs() < 1e-9, "{:?}", &v[knee..knee + 6]);
        }
        // Statistics: two "frames" per value, sums and sums of squares.
        let dim = layout.dim();
        let (mut sum, mut sum2) = (vec![0.0; dim], vec![0.0; dim]);
        for (d, (s, s2)) in sum.iter_mut().zip(&mut sum2).enumerate() {
            // Values x and -x + 2 c: mean c, std x - c; betas 0 and 1 vary by 1, beta 2 not.
            let (a, b) = match d {
                0 | 1 => (1.0, 3.0),
                2 => (5.0, 5.0),
                _ => (2.0, -2.0),
            };
            *s = a + b;
            *s2 = a * a + b * b;
        }
        let stats = layout.statistics(&sum, &sum2, 2.0);
        // Betas: z-scored; the constant one floored at a quarter of the block's pooled std.
        assert_eq!((stats.mean[0], stats.std[0]), (2.0, 1.0));
        let pooled = (2.0f64 / 10.0 * 1.0 + 7.0 / 10.0 * 4.0).sqrt();
        assert!(
            (stats.std[2] - 0.25 * pooled).abs() < 1e-12,
            "{}",
            stats.std[2]
        );
        // Rotations unscaled; velocities by their pooled root mean square (2).
        let rot = blocks[1].offset;
        assert_eq!((stats.mean[rot], stats.std[rot]), (0.0, 1.0));
        let vel = velocities.offset;
        assert_eq!((stats.mean[vel], stats.std[vel]), (0.0, 2.0));
        // The old layout z-scores everything and has no velocities.
        let old = ConditionLayout {
            scaling: ConditionScaling::ZScore,
            ..layout
        };
        assert_eq!(old.dim(), 415);
        assert!(
            old.blocks()
                .iter()
                .all(|b| b.scaling == BlockScaling::ZScore)
        );
    }

    /// The history layout is the bounded one followed by a rotation and a translation block
    /// per time constant, holding [`pose_history`]'s values in its order.
    #[test]
    fn the_history_layout_appends_the_weighted_past_to_the_bounded_one() {
        let frames = (0..40)
            .map(|k| {
                let mut pose = [0.0; POSE_DIM];
                pose[3 * 4] = 0.05 * k as f64;
                FramePose {
                    pose,
                    transl: [0.0, 0.9, 0.03 * k as f64],
                }
            })
            .collect();
        let motion = Motion::new("test", 30.0, frames).unwrap();
        let bounded = ConditionLayout {
            betas: 10,
            window: 2,
            material: MaterialRanges::default(),
            scaling: ConditionScaling::Bounded,
        };
        let layout = ConditionLayout {
            scaling: ConditionScaling::History,
            ..bounded
        };
        assert_eq!(
            layout.dim(),
            bounded.dim() + HISTORY_SECONDS.len() * HISTORY_VALUES
        );
        let names: Vec<String> = layout.blocks()[5..]
            .iter()
            .map(|b| b.name.clone())
            .collect();
        assert_eq!(
            names,
            [
                "history_100ms_rotations",
                "history_100ms_translation",
                "history_300ms_rotations",
                "history_300ms_translation",
                "history_1000ms_rotations",
                "history_1000ms_translation"
            ]
        );
        let material = Material {
            stretch: 120.0,
            density: 0.01,
            bending: 1e-4,
        };
        let v = layout.vector(&motion, 39, &[], &material).unwrap();
        let w = bounded.vector(&motion, 39, &[], &material).unwrap();
        assert_eq!(&v[..w.len()], &w[..]);
        assert_eq!(&v[w.len()..], &pose_history(&motion, 39).unwrap()[..]);
        // The walk forward lags behind the present in every history block's translation.
        for block in [6, 8, 10] {
            let forward = layout.blocks()[block].offset + 2;
            assert!(v[forward] < -0.01, "block {block}: {}", v[forward]);
        }
        assert_eq!(
            ConditionScaling::parse("history"),
            Some(ConditionScaling::History)
        );
        assert_eq!(ConditionScaling::History.name(), "history");
    }

    /// A manifest stores its layout; one written before the layout was stored (before
    /// 2026-12-04) lacks it and infers it from its blocks, which gives the same layout; once
    /// stored, the stored one is read back whatever the body says.
    #[test]
    fn a_manifest_stores_its_layout_and_an_older_one_infers_it() {
        let path = concat!(env!("CARGO_MANIFEST_DIR"), "/weights/tensors.json");
        let text = std::fs::read_to_string(path).unwrap();
        let stored: crate::data::TensorManifest = serde_json::from_str(&text).unwrap();
        let layout = stored
            .condition_layout
            .expect("the shipped model's manifest stores its layout");
        let mut old = stored.clone();
        old.condition_layout = None;
        let inferred = old.condition_layout(layout.betas);
        assert_eq!(inferred, layout);
        assert_eq!(inferred.scaling, ConditionScaling::Bounded);
        assert_eq!(inferred.dim(), old.condition_dim);
        let named = |blocks: &[Block]| -> Vec<(String, usize, usize)> {
            blocks
                .iter()
                .map(|b| (b.name.clone(), b.offset, b.size))
                .collect()
        };
        assert_eq!(named(&inferred.blocks()), named(&old.condition));
        let back: crate::data::TensorManifest =
            serde_json::from_str(&serde_json::to_string(&stored).unwrap()).unwrap();
        assert_eq!(back, stored);
        assert_eq!(back.condition_layout(16), layout, "the stored layout wins");
    }
}
