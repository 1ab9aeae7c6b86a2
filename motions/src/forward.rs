//! The SMPL forward pass (as the public smplx package's `lbs`): shape blend shapes, joint
//! regression, Rodrigues, pose blend shapes, the kinematic chain and linear blend skinning.
//!
//! Shaping is done once per set of betas ([`BodyModel::shape`]); posing a shaped body is the
//! per-frame work ([`BodyModel::pose`]), batched over frames in parallel with rayon.

use nalgebra::{Matrix3, Vector3};
use rayon::prelude::*;

use crate::body_model::BodyModel;
use crate::error::{Error, Result};
use crate::rotation::axis_angle_to_matrix;
use crate::skeleton::{NUM_JOINTS, POSE_DIM, POSE_FEATURE_DIM, mirror_joint};

/// A body with its shape applied: rest vertices and rest joints for one set of betas.
#[derive(Debug, Clone)]
pub struct ShapedBody {
    /// The betas used (truncated or zero-padded to the model's count).
    pub betas: Vec<f64>,
    /// Rest-pose vertices with shape blend shapes, metres.
    pub vertices: Vec<[f64; 3]>,
    /// Rest joints regressed from the shaped vertices, metres.
    pub joints: [[f64; 3]; NUM_JOINTS],
}

impl ShapedBody {
    /// Its height in the rest pose: the vertical (y) extent of its vertices, metres.
    pub fn height(&self) -> f64 {
        vertical_extent(&self.vertices)
    }
}

/// The vertical (y) extent of `vertices`.
fn vertical_extent(vertices: &[[f64; 3]]) -> f64 {
    let (lo, hi) = vertices.iter().fold((f64::MAX, f64::MIN), |(lo, hi), v| {
        (lo.min(v[1]), hi.max(v[1]))
    });
    hi - lo
}

/// A rigid transform: rotation then translation (p' = R p + t).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Transform {
    /// Rotation.
    pub rotation: Matrix3<f64>,
    /// Translation, metres.
    pub translation: Vector3<f64>,
}

impl Transform {
    fn apply(&self, p: &Vector3<f64>) -> Vector3<f64> {
        self.rotation * p + self.translation
    }
}

/// One posed frame: vertices, joints and each joint's world transform.
#[derive(Debug, Clone)]
pub struct PosedBody {
    /// Posed vertices (model vertex order), metres, translation included.
    pub vertices: Vec<[f64; 3]>,
    /// Posed joint positions, metres, translation included.
    pub joints: [[f64; 3]; NUM_JOINTS],
    /// World transform of each joint's frame (smplx's `G` plus the translation): rotation of
    /// the segment and position of its joint.
    pub transforms: [Transform; NUM_JOINTS],
}

impl PosedBody {
    /// The vertical (y) extent of its vertices, metres.
    pub fn height(&self) -> f64 {
        vertical_extent(&self.vertices)
    }
}

/// Pose input of one frame: 72 axis-angle values (global orientation, then 23 body joints,
/// radians) and the root translation (metres).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct FramePose {
    /// Axis-angle rotations of the 24 joints relative to their parents.
    pub pose: [f64; POSE_DIM],
    /// Root translation, added after skinning.
    pub transl: [f64; 3],
}

impl FramePose {
    /// The pose's mirror image through the sagittal plane x = 0: left and right joints
    /// swapped, each rotation reflected (an axis-angle vector is a pseudovector, so it keeps
    /// its x component and negates y and z), the root moved to -x. On a body model symmetric
    /// about x = 0 (the default body is, to 0.03 mm), the posed body is the mirror image of
    /// this pose's posed body, vertex for mirrored vertex.
    pub fn mirrored(&self) -> FramePose {
        let mut pose = [0.0; POSE_DIM];
        for j in 0..NUM_JOINTS {
            let from = 3 * mirror_joint(j);
            pose[3 * j] = self.pose[from];
            pose[3 * j + 1] = -self.pose[from + 1];
            pose[3 * j + 2] = -self.pose[from + 2];
        }
        let [x, y, z] = self.transl;
        FramePose {
            pose,
            transl: [-x, y, z],
        }
    }
}

impl BodyModel {
    /// Applies shape coefficients. Betas beyond the model's count are ignored (as AMASS's 16
    /// betas on a 10-beta model), missing ones are zero. Non-finite betas are an error.
    pub fn shape(&self, betas: &[f64]) -> Result<ShapedBody> {
        if let Some(i) = betas.iter().position(|b| !b.is_finite()) {
            return Err(Error::NotFinite {
                what: "beta",
                index: i,
            });
        }
        let nb = self.num_betas;
        let mut used = vec![0.0; nb];
        for (u, b) in used.iter_mut().zip(betas) {
            *u = *b;
        }
        let vertices: Vec<[f64; 3]> = self
            .v_template
            .iter()
            .enumerate()
            .map(|(v, rest)| {
                let mut p = *rest;
                for (c, pc) in p.iter_mut().enumerate() {
                    let dirs = &self.shapedirs[(v * 3 + c) * nb..(v * 3 + c + 1) * nb];
                    *pc += dirs.iter().zip(&used).map(|(d, b)| d * b).sum::<f64>();
                }
                p
            })
            .collect();
        let mut joints = [[0.0; 3]; NUM_JOINTS];
        for (j, row) in self.j_regressor.iter().enumerate() {
            for &(v, w) in row {
                for c in 0..3 {
                    joints[j][c] += w * vertices[v as usize][c];
                }
            }
        }
        Ok(ShapedBody {
            betas: used,
            vertices,
            joints,
        })
    }

    /// World transforms of the joints for one pose (no vertices): the cheap part of the pass,
    /// used where only the skeleton matters (foot planting, pose windows).
    pub fn joint_transforms(
        &self,
        shaped: &ShapedBody,
        frame: &FramePose,
    ) -> [Transform; NUM_JOINTS] {
        let rotations = local_rotations(&frame.pose);
        self.chain(shaped, &rotations, frame.transl)
    }

    fn chain(
        &self,
        shaped: &ShapedBody,
        rotations: &[Matrix3<f64>; NUM_JOINTS],
        transl: [f64; 3],
    ) -> [Transform; NUM_JOINTS] {
        let rest = |j: usize| Vector3::from(shaped.joints[j]);
        let mut g = [Transform {
            rotation: Matrix3::identity(),
            translation: Vector3::zeros(),
        }; NUM_JOINTS];
        for j in 0..NUM_JOINTS {
            g[j] = match self.parents[j] {
                None => Transform {
                    rotation: rotations[0],
                    translation: rest(0) + Vector3::from(transl),
                },
                Some(p) => Transform {
                    rotation: g[p].rotation * rotations[j],
                    translation: g[p].apply(&(rest(j) - rest(p))),
                },
            };
        }
        g
    }

    /// Poses a shaped body. Errors on non-finite pose or translation values.
    pub fn pose(&self, shaped: &ShapedBody, frame: &FramePose) -> Result<PosedBody> {
        if let Some(i) = frame
            .pose
            .iter()
            .chain(&frame.transl)
            .position(|v| !v.is_finite())
        {
            return Err(Error::NotFinite {
                what: "pose/translation value",
                index: i,
            });
        }
        let rotations = local_rotations(&frame.pose);
        let g = self.chain(shaped, &rotations, frame.transl);
        // Skinning transforms: A_j = G_j with translation t_j - R_j J_j (rest joint at origin).
        let a: [Transform; NUM_JOINTS] = std::array::from_fn(|j| Transform {
            rotation: g[j].rotation,
            translation: g[j].translation - g[j].rotation * Vector3::from(shaped.joints[j]),
        });
        let feature = self.posedirs.as_ref().map(|_| pose_feature(&rotations));
        let vertices = (0..shaped.vertices.len())
            .map(|v| {
                let mut rest = Vector3::from(shaped.vertices[v]);
                if let (Some(posedirs), Some(feature)) = (&self.posedirs, &feature) {
                    for c in 0..3 {
                        let dirs = &posedirs
                            [(v * 3 + c) * POSE_FEATURE_DIM..(v * 3 + c + 1) * POSE_FEATURE_DIM];
                        rest[c] += dirs.iter().zip(feature).map(|(d, f)| d * f).sum::<f64>();
                    }
                }
                let range = self.skin_start[v] as usize..self.skin_start[v + 1] as usize;
                let mut out = Vector3::zeros();
                for &(j, w) in &self.skin[range] {
                    out += a[j as usize].apply(&rest) * w;
                }
                out.into()
            })
            .collect();
        Ok(PosedBody {
            vertices,
            joints: std::array::from_fn(|j| g[j].translation.into()),
            transforms: g,
        })
    }

    /// Poses a shaped body for many frames in parallel (rayon), in frame order.
    pub fn pose_batch(&self, shaped: &ShapedBody, frames: &[FramePose]) -> Result<Vec<PosedBody>> {
        frames.par_iter().map(|f| self.pose(shaped, f)).collect()
    }
}

/// Local rotation matrices of the 24 joints.
fn local_rotations(pose: &[f64; POSE_DIM]) -> [Matrix3<f64>; NUM_JOINTS] {
    std::array::from_fn(|j| axis_angle_to_matrix([pose[3 * j], pose[3 * j + 1], pose[3 * j + 2]]))
}

/// The pose-blend-shape feature: (R_j - I) of joints 1..23, each flattened row-major.
fn pose_feature(rotations: &[Matrix3<f64>; NUM_JOINTS]) -> [f64; POSE_FEATURE_DIM] {
    let mut f = [0.0; POSE_FEATURE_DIM];
    for j in 1..NUM_JOINTS {
        let d = rotations[j] - Matrix3::identity();
        for r in 0..3 {
            for c in 0..3 {
                f[(j - 1) * 9 + r * 3 + c] = d[(r, c)];
            }
        }
    }
    f
}
