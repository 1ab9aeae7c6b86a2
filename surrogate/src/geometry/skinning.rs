//! The template skinned to a body by linear blend skinning, the base of the `lbs_residual`
//! target: every garment vertex borrows the skinning weights of its nearest body vertex on the
//! template body (betas 0, canonical A-pose), with the leg joints' weights folded into the
//! pelvis so skirts and dresses do not split into trousers (measured: plain nearest weights
//! put 57% of the skirt on the legs and stretch its seams 23x; folded, within 0.02 cm of the
//! best per garment; docs/SURROGATE.md), then smoothed over the garment's own edges so the
//! skinned template has no creases where nearest body vertices jump between limbs (a creased
//! base makes a residual that texels cannot hold: docs/SURROGATE.md), plus the nearest body
//! vertex's shape offset.

use kiddo::SquaredEuclidean;
use kiddo::immutable::float::kdtree::ImmutableKdTree;
use motions::{BodyModel, FramePose, NUM_JOINTS, ShapedBody, Transform, canonical_a_pose};
use nalgebra::{Matrix3, Vector3};

use crate::error::Result;

/// Joints whose weights go to the pelvis: hips, knees, ankles, feet.
pub const FOLDED_JOINTS: [usize; 8] = [1, 2, 4, 5, 7, 8, 10, 11];

/// Rounds of averaging each vertex's weights with its neighbours' over the garment's edges
/// (measured on walk at 64: tank_loose's worst round-trip vertex 7.5 cm unsmoothed, 1.3 at 5
/// rounds, 0.7 at 20, 0.6 at 60; the mean residual also falls, 2.07 -> 1.98 cm).
pub const SMOOTHING_ROUNDS: usize = 50;

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

/// Averages every vertex's weights with its neighbours' (over the triangles' edges), `rounds`
/// times (Jacobi: each round reads the previous one); rows keep summing to 1.
fn smooth(weights: &mut [[f64; NUM_JOINTS]], triangles: &[[u32; 3]], rounds: usize) {
    let neighbours = garments::vertex_neighbours(weights.len(), triangles);
    for _ in 0..rounds {
        let previous = weights.to_vec();
        for (v, w) in weights.iter_mut().enumerate() {
            let ring = &neighbours[v];
            for (j, x) in w.iter_mut().enumerate() {
                let sum: f64 = ring.iter().map(|&u| previous[u as usize][j]).sum();
                *x = (previous[v][j] + sum) / (1 + ring.len()) as f64;
            }
        }
    }
}

/// The canonical A-pose without root translation, the pose templates are made in.
fn canonical_frame() -> FramePose {
    FramePose {
        pose: canonical_a_pose(),
        transl: [0.0; 3],
    }
}

/// A weight row's joints with weight above 1e-9.
fn sparse(w: &[f64; NUM_JOINTS]) -> Vec<(usize, f64)> {
    w.iter()
        .enumerate()
        .filter(|(_, x)| **x > 1e-9)
        .map(|(j, x)| (j, *x))
        .collect()
}

/// Per point, the skinning weights of its nearest vertex of `body` (the legs' folded into the
/// pelvis with `fold`), smoothed `rounds` times over `triangles`, and that vertex.
fn nearest_weights(
    model: &BodyModel,
    body: &[[f64; 3]],
    points: &[[f64; 3]],
    triangles: &[[u32; 3]],
    rounds: usize,
    fold: bool,
) -> (Vec<[f64; NUM_JOINTS]>, Vec<u32>) {
    let tree: ImmutableKdTree<f64, u32, 3, 32> = ImmutableKdTree::new_from_slice(body);
    let mut dense = Vec::with_capacity(points.len());
    let mut body_vertex = Vec::with_capacity(points.len());
    for p in points {
        let b = tree.nearest_one::<SquaredEuclidean>(p).item;
        let mut w = [0.0; NUM_JOINTS];
        for &(j, x) in model.skinning_weights(b as usize) {
            let j = j as usize;
            w[if fold && FOLDED_JOINTS.contains(&j) {
                0
            } else {
                j
            }] += x;
        }
        dense.push(w);
        body_vertex.push(b);
    }
    smooth(&mut dense, triangles, rounds);
    (dense, body_vertex)
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
    /// The skinning of a template (rest positions on the template body, `triangles` over
    /// them) on `model`, its weights smoothed `rounds` times over the template's edges.
    pub fn new(
        model: &BodyModel,
        template: &[[f64; 3]],
        triangles: &[[u32; 3]],
        rounds: usize,
    ) -> Result<Self> {
        Self::build(model, template, triangles, rounds, true)
    }

    /// Plain nearest-body-vertex skinning: the legs not folded, no smoothing (the
    /// `lbs_nearest` baseline, which turns skirts into trousers).
    pub fn nearest(model: &BodyModel, template: &[[f64; 3]]) -> Result<Self> {
        Self::build(model, template, &[], 0, false)
    }

    fn build(
        model: &BodyModel,
        template: &[[f64; 3]],
        triangles: &[[u32; 3]],
        rounds: usize,
        fold: bool,
    ) -> Result<Self> {
        let shaped = model.shape(&[])?;
        let body = model.pose(&shaped, &canonical_frame())?;
        let a = skinning_transforms(&body.transforms, &shaped);
        let (dense, body_vertex) =
            nearest_weights(model, &body.vertices, template, triangles, rounds, fold);
        let mut weights = Vec::with_capacity(template.len());
        let mut unposed = Vec::with_capacity(template.len());
        for (p, w) in template.iter().zip(&dense) {
            let w = sparse(w);
            let m = blend(&w, &a);
            let inverse = m.linear.try_inverse().unwrap_or_else(Matrix3::identity);
            unposed.push(inverse * (Vector3::from(*p) - m.translation));
            weights.push(w);
        }
        Ok(Self {
            weights,
            body_vertex,
            unposed,
        })
    }

    /// Each vertex's position unposed to the T-pose of the default body, m.
    pub fn t_pose(&self) -> impl Iterator<Item = [f64; 3]> + '_ {
        self.unposed.iter().map(|x| [x[0], x[1], x[2]])
    }

    /// Each vertex's nearest vertex of the canonical body.
    pub fn body_vertices(&self) -> &[u32] {
        &self.body_vertex
    }

    /// Vertex `v`'s summed weight on `joints`.
    pub fn share(&self, v: usize, joints: &[usize]) -> f64 {
        self.weights[v]
            .iter()
            .filter(|(j, _)| joints.contains(j))
            .map(|(_, w)| w)
            .sum()
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
    fn smoothing_averages_over_edges_and_keeps_rows_summing_to_one() {
        // A strip of four vertices: weights jump from joint 0 to joint 3 in the middle.
        let mut w = vec![[0.0; NUM_JOINTS]; 4];
        w[0][0] = 1.0;
        w[1][0] = 1.0;
        w[2][3] = 1.0;
        w[3][3] = 1.0;
        smooth(&mut w, &[[0, 1, 2], [1, 3, 2]], 1);
        for row in &w {
            assert!((row.iter().sum::<f64>() - 1.0).abs() < 1e-12, "{row:?}");
        }
        // Vertex 1 (neighbours 0, 2, 3) becomes (1 + 1 + 0 + 0) / 4 on joint 0.
        assert!((w[1][0] - 0.5).abs() < 1e-12, "{:?}", w[1]);
        assert!((w[0][0] - 2.0 / 3.0).abs() < 1e-12, "{:?}", w[0]);
    }

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
        let skinning = Skinning::new(&model, &template, &[], SMOOTHING_ROUNDS).unwrap();
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
