//! The canonical frame of one output frame: the current frame's root motion removed from the
//! cloth, so a model sees the garment as if the body stood where the template was made, and
//! restored after prediction.
//!
//! `x_c = R^T (x - p) + p0`, with `p` the frame's posed pelvis (root joint), `p0` the
//! template body's pelvis (betas 0, no translation) and `R` the removed rotation: the heading
//! alone (rotation about +y, as `Motion::pose_window` removes it; tilt is kept) or the whole
//! root orientation. The default is chosen by measurement (docs/SURROGATE.md).

use motions::rotation::axis_angle_to_matrix;
use nalgebra::{Matrix3, Rotation3, Vector3};
use serde::{Deserialize, Serialize};

/// Which part of the root rotation the canonical frame removes.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum RootRemoval {
    /// The heading (rotation about the vertical axis) only; tilt relative to gravity stays.
    #[default]
    Heading,
    /// The whole root orientation.
    Full,
}

/// The rigid map of one frame into its canonical frame and back.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Canonical {
    rotation: Matrix3<f64>,
    pelvis: Vector3<f64>,
    rest_pelvis: Vector3<f64>,
}

impl Canonical {
    /// The canonical frame of a frame with root orientation `global_orient` (axis-angle),
    /// posed pelvis `pelvis` (m) and template pelvis `rest_pelvis` (m).
    pub fn new(
        removal: RootRemoval,
        global_orient: [f64; 3],
        pelvis: [f64; 3],
        rest_pelvis: [f64; 3],
    ) -> Self {
        let root = axis_angle_to_matrix(global_orient);
        let rotation = match removal {
            RootRemoval::Full => root,
            RootRemoval::Heading => {
                let forward = root * Vector3::z();
                let heading = forward.x.atan2(forward.z);
                *Rotation3::from_axis_angle(&Vector3::y_axis(), heading).matrix()
            }
        };
        Self {
            rotation,
            pelvis: Vector3::from(pelvis),
            rest_pelvis: Vector3::from(rest_pelvis),
        }
    }

    /// A world point in the canonical frame.
    pub fn to_canonical(&self, p: [f64; 3]) -> [f64; 3] {
        (self.rotation.transpose() * (Vector3::from(p) - self.pelvis) + self.rest_pelvis).into()
    }

    /// A canonical point back in the world.
    pub fn to_world(&self, q: [f64; 3]) -> [f64; 3] {
        (self.rotation * (Vector3::from(q) - self.rest_pelvis) + self.pelvis).into()
    }

    /// A world direction (a gradient) in the canonical frame: rotated only.
    pub fn direction_to_canonical(&self, d: [f64; 3]) -> [f64; 3] {
        (self.rotation.transpose() * Vector3::from(d)).into()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn canonicalization_then_its_inverse_returns_the_input() {
        for removal in [RootRemoval::Heading, RootRemoval::Full] {
            let c = Canonical::new(
                removal,
                [0.3, 1.2, -0.4],
                [0.5, 0.9, -2.0],
                [0.0, 0.93, 0.01],
            );
            for p in [[0.0, 0.0, 0.0], [1.5, -0.2, 3.0], [-0.7, 1.7, 0.2]] {
                let back = c.to_world(c.to_canonical(p));
                let error = (0..3).map(|k| (back[k] - p[k]).abs()).fold(0.0, f64::max);
                assert!(error < 1e-12, "{removal:?}: {p:?} came back as {back:?}");
            }
            // The pelvis goes to the template's pelvis.
            let q = c.to_canonical([0.5, 0.9, -2.0]);
            assert!((Vector3::from(q) - Vector3::new(0.0, 0.93, 0.01)).norm() < 1e-12);
        }
    }

    #[test]
    fn heading_removal_keeps_the_vertical() {
        // A body turned 90 degrees about +y and tilted: its heading frame keeps +y vertical.
        let c = Canonical::new(
            RootRemoval::Heading,
            [0.2, std::f64::consts::FRAC_PI_2, 0.0],
            [0.0; 3],
            [0.0; 3],
        );
        let up = c.to_canonical([0.0, 1.0, 0.0]);
        assert!((up[1] - 1.0).abs() < 1e-12, "{up:?}");
    }
}
