//! Mirror augmentation (`dataset tensors --mirror`): a recorded sequence reflected through the
//! body's sagittal plane (x -> -x) is another sequence of the same physics, since the body,
//! gravity and the engine are symmetric. The motion is mirrored joint by joint
//! ([`motions::FramePose::mirrored`]); the cloth is carried to the template's own vertices by
//! the template's mirror correspondence (each vertex takes the mirror image of the cloth at the
//! template point nearest its own mirror image), so a mirrored sample keeps the template, its
//! UV layout and its geometry image. A kick with the left leg becomes one with the right: twice
//! the motions for the same synthesis.
//!
//! It holds where the template is symmetric (a library design is, up to its drape's folds) and
//! the body model is (the default body is, to 0.03 mm); [`TemplateMirror::is_symmetric`] and
//! [`body_asymmetry_m`] say how far each is from it.

use kiddo::SquaredEuclidean;
use kiddo::immutable::float::kdtree::ImmutableKdTree;
use motions::BodyModel;
use parry3d::math::Vector;
use parry3d::query::PointQueryWithLocation;
use parry3d::shape::TriMesh;
use sim::recording::TemplateArrays;

use super::sequence::Sequence;
use crate::error::{Error, Result};

/// The largest mean distance (m) from a template's mirrored vertices to its surface at which
/// the template is mirrored unless told otherwise (`--mirror-max-gap-cm`): a drape's folds leave
/// sleeveless library designs 0.04-0.3 cm off and sleeved ones 0.2-1.3 cm.
pub const DEFAULT_MIRROR_MAX_GAP_M: f64 = 0.005;

/// The largest mean distance (m) from a body model's mirrored rest vertices to its nearest
/// vertex at which `--mirror` is allowed.
pub const MAX_BODY_ASYMMETRY_M: f64 = 0.002;

/// Mirror image through the plane x = 0.
fn reflect([x, y, z]: [f64; 3]) -> [f64; 3] {
    [-x, y, z]
}

/// A template's mirror correspondence.
#[derive(Debug, Clone)]
pub struct TemplateMirror {
    /// Per vertex: the triangle, and the barycentric weights in it, of the template point
    /// nearest the vertex's mirror image.
    sources: Vec<([u32; 3], [f64; 3])>,
    /// Mean distance from a vertex's mirror image to the template surface, m.
    pub mean_gap_m: f64,
}

impl TemplateMirror {
    /// The correspondence of `template` (`source` names it in errors).
    pub fn of_template(template: &TemplateArrays, source: &str) -> Result<Self> {
        let vertices: Vec<Vector> = template
            .positions
            .iter()
            .map(|p| Vector::new(p[0] as f32, p[1] as f32, p[2] as f32))
            .collect();
        let mesh = TriMesh::new(vertices, template.triangles.clone()).map_err(|e| Error::File {
            path: source.to_string(),
            problem: format!("the template is not a triangle mesh parry3d takes: {e}").into(),
        })?;
        let mut gap = 0.0;
        let sources = template
            .positions
            .iter()
            .map(|&p| {
                let [x, y, z] = reflect(p);
                let point = Vector::new(x as f32, y as f32, z as f32);
                let (projection, (face, location)) =
                    mesh.project_local_point_and_get_location(point, false);
                gap += f64::from((projection.point - point).length());
                let weights = location
                    .barycentric_coordinates()
                    .unwrap_or([1.0, 0.0, 0.0])
                    .map(f64::from);
                (template.triangles[face as usize], weights)
            })
            .collect();
        Ok(Self {
            sources,
            mean_gap_m: gap / template.positions.len().max(1) as f64,
        })
    }

    /// Whether the template is symmetric within `max_gap_m` (its mean gap, m).
    pub fn is_symmetric(&self, max_gap_m: f64) -> bool {
        self.mean_gap_m <= max_gap_m
    }

    /// One frame's cloth (world, m) mirrored onto the template's vertices.
    pub fn cloth(&self, cloth: &[[f64; 3]]) -> Vec<[f64; 3]> {
        self.sources
            .iter()
            .map(|(corners, weights)| {
                let mut p = [0.0; 3];
                for (&v, w) in corners.iter().zip(weights) {
                    for (c, x) in p.iter_mut().zip(cloth[v as usize]) {
                        *c += w * x;
                    }
                }
                reflect(p)
            })
            .collect()
    }

    /// The template's own mirror image on its vertices (`positions` are its rest positions):
    /// the rest shape a mirrored sequence's cloth hangs from, which differs from the template
    /// by its asymmetry.
    pub fn template(&self, positions: &[[f64; 3]]) -> Vec<[f64; 3]> {
        self.cloth(positions)
    }

    /// The whole sequence mirrored: the body's motion and every frame's cloth.
    pub fn sequence(&self, s: &Sequence) -> Sequence {
        let mut meta = s.meta.clone();
        meta.motion = format!("{}~mirrored", meta.motion);
        Sequence {
            source: format!("{} (mirrored)", s.source),
            meta,
            template: s.template.clone(),
            poses: s.poses.iter().map(|p| p.mirrored()).collect(),
            betas: s.betas.clone(),
            garment: s.garment.iter().map(|f| self.cloth(f)).collect(),
        }
    }
}

/// Mean distance (m) from each rest vertex of `model`, mirrored, to its nearest rest vertex: 0
/// for a body symmetric about x = 0.
pub fn body_asymmetry_m(model: &BodyModel) -> f64 {
    let template = model.template();
    let tree: ImmutableKdTree<f64, u32, 3, 32> = ImmutableKdTree::new_from_slice(template);
    let total: f64 = template
        .iter()
        .map(|&p| {
            tree.nearest_one::<SquaredEuclidean>(&reflect(p))
                .distance
                .sqrt()
        })
        .sum();
    total / template.len().max(1) as f64
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A strip of two triangles symmetric about x = 0, its vertices in an order that is not.
    fn strip() -> TemplateArrays {
        TemplateArrays {
            positions: vec![
                [-0.1, 0.0, 0.0],
                [0.1, 0.0, 0.0],
                [0.1, 0.2, 0.0],
                [-0.1, 0.2, 0.0],
                [0.0, 0.1, 0.05],
            ],
            triangles: vec![[0, 1, 4], [1, 2, 4], [2, 3, 4], [3, 0, 4]],
            uvs: vec![[0.0; 2]; 5],
            uv_triangles: vec![[0, 1, 4], [1, 2, 4], [2, 3, 4], [3, 0, 4]],
        }
    }

    /// Each vertex of a symmetric template finds its mirror partner (gap 0); the cloth it
    /// takes is the partner's, reflected, so mirroring twice gives the cloth back.
    #[test]
    fn a_symmetric_template_swaps_partners_and_mirroring_twice_is_the_identity() {
        let template = strip();
        let mirror = TemplateMirror::of_template(&template, "strip").unwrap();
        assert!(mirror.mean_gap_m < 1e-7 && mirror.is_symmetric(DEFAULT_MIRROR_MAX_GAP_M));
        let cloth = vec![
            [-0.12, -0.05, 0.01],
            [0.09, -0.04, 0.02],
            [0.11, 0.18, -0.01],
            [-0.08, 0.21, 0.03],
            [0.01, 0.1, 0.06],
        ];
        let once = mirror.cloth(&cloth);
        // Vertex 0's partner is vertex 1: it takes vertex 1's cloth, reflected.
        let expected = [-0.09, -0.04, 0.02];
        assert!(
            (0..3).all(|c| (once[0][c] - expected[c]).abs() < 1e-6),
            "{once:?}"
        );
        let twice = mirror.cloth(&once);
        for (a, b) in twice.iter().zip(&cloth) {
            assert!((0..3).all(|c| (a[c] - b[c]).abs() < 1e-6), "{a:?} {b:?}");
        }
    }

    /// A template bent to one side is not symmetric, and says by how much.
    #[test]
    fn a_lopsided_template_is_not_mirrored() {
        let mut template = strip();
        template.positions[4] = [0.03, 0.1, 0.05];
        template.positions[1][2] = 0.02;
        let mirror = TemplateMirror::of_template(&template, "strip").unwrap();
        assert!(
            mirror.mean_gap_m > DEFAULT_MIRROR_MAX_GAP_M,
            "{}",
            mirror.mean_gap_m
        );
        assert!(!mirror.is_symmetric(DEFAULT_MIRROR_MAX_GAP_M) && mirror.is_symmetric(0.05));
    }

    #[test]
    fn the_default_body_is_symmetric() {
        let gap = body_asymmetry_m(&BodyModel::default_body());
        assert!(gap < 1e-6, "{gap} m");
    }
}
