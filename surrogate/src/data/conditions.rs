//! The condition vector of one frame: body shape, pose window and material, in a documented
//! layout (names, offsets, sizes) that the tensors' manifest records.
//!
//! | name | size | content |
//! |---|---|---|
//! | `betas` | B (the body model's, 10 for the default body) | shape coefficients as recorded |
//! | `rotations_6d` | (L + 1) x 22 x 6 | the window's joint rotations (body joints, hands dropped), oldest frame first, each as the first two columns of its rotation matrix; root orientations with the current frame's heading removed (`Motion::pose_window`) |
//! | `translations` | L x 3 | the L earlier frames' root translations relative to the current frame's, in its heading frame, m |
//! | `material` | 3 | k_s, rho and log10 k_b, each mapped linearly from the dataset's range to [-1, 1] |

use motions::Motion;
use motions::rotation::axis_angle_to_matrix;
use serde::{Deserialize, Serialize};
use sim::Material;
use sim::dataset::MaterialRanges;

use crate::error::Result;

/// Joints whose rotations enter the condition: SMPL's 22 body joints (the hands are dropped:
/// the built-in motions and AMASS imports leave them at rest).
pub const CONDITION_JOINTS: usize = 22;

/// One named block of the condition vector.
#[derive(Debug, Clone, PartialEq, Eq, Serialize, Deserialize)]
pub struct Block {
    /// Name.
    pub name: String,
    /// First index.
    pub offset: usize,
    /// Length.
    pub size: usize,
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
}

impl ConditionLayout {
    /// The named blocks, in order.
    pub fn blocks(&self) -> Vec<Block> {
        let sizes = [
            ("betas", self.betas),
            ("rotations_6d", (self.window + 1) * CONDITION_JOINTS * 6),
            ("translations", self.window * 3),
            ("material", 3),
        ];
        let mut offset = 0;
        sizes
            .into_iter()
            .map(|(name, size)| {
                let block = Block {
                    name: name.to_string(),
                    offset,
                    size,
                };
                offset += size;
                block
            })
            .collect()
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
                let m = axis_angle_to_matrix([pose[3 * j], pose[3 * j + 1], pose[3 * j + 2]]);
                for col in 0..2 {
                    out.extend((0..3).map(|row| m[(row, col)]));
                }
            }
        }
        for t in &window.transl[..self.window] {
            out.extend(t);
        }
        let m = self.material;
        out.push(to_unit(material.stretch, m.k_s));
        out.push(to_unit(material.density, m.rho));
        out.push(to_unit(material.bending.log10(), m.log10_k_b));
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
}
