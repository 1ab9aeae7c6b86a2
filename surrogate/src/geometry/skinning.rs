//! The template skinned to a body by linear blend skinning, the base of the `lbs_residual`
//! target: every garment vertex borrows the skinning weights of its nearest body vertex on the
//! template body (betas 0, canonical A-pose), with the leg joints' weights folded into the
//! pelvis so skirts and dresses do not split into trousers (measured: plain nearest weights
//! put 57% of the skirt on the legs and stretch its seams 23x; folded, within 0.02 cm of the
//! best per garment; docs/SURROGATE.md), plus that body vertex's shape offset.

use kiddo::SquaredEuclidean;
use kiddo::immutable::float::kdtree::ImmutableKdTree;
use motions::{BodyModel, FramePose, NUM_JOINTS, ShapedBody, Transform, canonical_a_pose};
use nalgebra::{Matrix3, Vector3};

use crate::error::Result;

/// Joints whose weights go to the pelvis: hips, knees, ankles, feet.
pub const FOLDED_JOINTS: [usize; 8] = [1, 2, 4, 5, 7, 8, 10, 11];

/// An affine map x -> R x + t.
#[derive(Debug, Clone, Copy, PartialEq)]
struct Affine {
    linear: Matrix3<f64>,
    translation: Vector3<f64>,
}

impl Affine {
    fn apply(&self, x: Vector3<f64>) -> Vector3<f64> {
        self.linear * x + self.translation
    }
}

/// Skinning transforms A_j (rest joint at the origin) from the joints' world transforms.
fn skinning_transforms(g: &[Transform; NUM_JOINTS], shaped: &ShapedBody) -> [Affine; NUM_JOINTS] {
    std::array::from_fn(|j| Affine {
        linear: g[j].rotation,
        translation: g[j].translation - g[j].rotation * Vector3::from(shaped.joints[j]),
    })
}

/// The blend sum_j w_j A_j.
fn blend(weights: &[(usize, f64)], a: &[Affine; NUM_JOINTS]) -> Affine {
    let mut out = Affine {
        linear: Matrix3::zeros(),
        translation: Vector3::zeros(),
    };
    for &(j, w) in weights {
        out.linear += a[j].linear * w;
        out.translation += a[j].translation * w;
    }
    out
}

/// A template's skinning: per garment vertex its weights, its body vertex and its unposed
/// (T-pose, betas 0) position.
#[derive(Debug, Clone)]
pub struct Skinning {
    weights: Vec<Vec<(usize, f64)>>,
    body_vertex: Vec<u32>,
    unposed: Vec<Vector3<f64>>,
}

impl Skinning {
    /// The skinning of a template (rest positions on the template body) on `model`.
    pub fn new(model: &BodyModel, template: &[[f64; 3]]) -> Result<Self> {
        let shaped = model.shape(&[])?;
        let canonical = FramePose {
            pose: canonical_a_pose(),
            transl: [0.0; 3],
        };
        let body = model.pose(&shaped, &canonical)?;
        let tree: ImmutableKdTree<f64, u32, 3, 32> =
            ImmutableKdTree::new_from_slice(&body.vertices);
        let a = skinning_transforms(&body.transforms, &shaped);
        let mut weights = Vec::with_capacity(template.len());
        let mut body_vertex = Vec::with_capacity(template.len());
        let mut unposed = Vec::with_capacity(template.len());
        for p in template {
            let b = tree.nearest_one::<SquaredEuclidean>(p).item;
            let mut w = [0.0; NUM_JOINTS];
            for &(j, x) in model.skinning_weights(b as usize) {
                let j = if FOLDED_JOINTS.contains(&(j as usize)) {
                    0
                } else {
                    j as usize
                };
                w[j] += x;
            }
            let w: Vec<(usize, f64)> = w
                .iter()
                .enumerate()
                .filter(|(_, x)| **x != 0.0)
                .map(|(j, x)| (j, *x))
                .collect();
            let m = blend(&w, &a);
            let inverse = m.linear.try_inverse().unwrap_or_else(Matrix3::identity);
            unposed.push(inverse * (Vector3::from(*p) - m.translation));
            weights.push(w);
            body_vertex.push(b);
        }
        Ok(Self {
            weights,
            body_vertex,
            unposed,
        })
    }

    /// The template skinned to the body of shape `shaped` posed by `frame` (world, m).
    pub fn pose(&self, model: &BodyModel, shaped: &ShapedBody, frame: &FramePose) -> Vec<[f64; 3]> {
        let g = model.joint_transforms(shaped, frame);
        let a = skinning_transforms(&g, shaped);
        let rest = model.template();
        self.unposed
            .iter()
            .zip(&self.weights)
            .zip(&self.body_vertex)
            .map(|((x, w), &b)| {
                let b = b as usize;
                let offset = Vector3::from(shaped.vertices[b]) - Vector3::from(rest[b]);
                blend(w, &a).apply(x + offset).into()
            })
            .collect()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_skinned_template_on_the_template_body_is_the_template() {
        let model = BodyModel::default_body();
        let shaped = model.shape(&[]).unwrap();
        let canonical = FramePose {
            pose: canonical_a_pose(),
            transl: [0.0; 3],
        };
        let body = model.pose(&shaped, &canonical).unwrap();
        // Points 1 cm outside some body vertices.
        let template: Vec<[f64; 3]> = body
            .vertices
            .iter()
            .step_by(97)
            .map(|v| [v[0], v[1], v[2] + 0.01])
            .collect();
        let skinning = Skinning::new(&model, &template).unwrap();
        let posed = skinning.pose(&model, &shaped, &canonical);
        for (p, q) in posed.iter().zip(&template) {
            let d = (Vector3::from(*p) - Vector3::from(*q)).norm();
            assert!(d < 1e-9, "{p:?} vs {q:?}");
        }
        // A translated frame moves every vertex by the translation.
        let moved = FramePose {
            transl: [0.5, 0.0, -1.0],
            ..canonical
        };
        let posed = skinning.pose(&model, &shaped, &moved);
        let d = Vector3::from(posed[3]) - Vector3::from(template[3]);
        assert!((d - Vector3::new(0.5, 0.0, -1.0)).norm() < 1e-9, "{d}");
    }
}
