//! Where the body is from each garment vertex: the offset from the template skinned to the
//! frame's body to the nearest point of the posed body surface, and that point's outward
//! normal, both in the frame's canonical frame. The skinned base alone does not say how far
//! the body is: a sleeve vertex skinned 2 cm off the arm and one skinned onto it look alike,
//! though the first hangs and the second rests on the skin.

use motions::{BodyModel, ShapedBody};
use sim::Vec3;
use sim::obstacles::MeshSurface;

use super::canonical::Canonical;
use super::target::FrameBody;
use crate::error::Result;

/// A posed body's surface kept from frame to frame: reshaped only when the shape changes,
/// refit in place rather than rebuilt (the body's topology never changes).
#[derive(Default)]
pub struct PosedSurface {
    shaped: Option<ShapedBody>,
    surface: Option<MeshSurface>,
}

impl PosedSurface {
    /// The surface of `body` on `model`.
    pub fn at(&mut self, model: &BodyModel, body: FrameBody) -> Result<&MeshSurface> {
        if self.shaped.as_ref().is_none_or(|s| s.betas != body.betas) {
            self.shaped = Some(model.shape(body.betas)?);
        }
        let shaped = self.shaped.as_ref().expect("set above");
        let vertices: Vec<Vec3> = model
            .pose(shaped, body.pose)?
            .vertices
            .into_iter()
            .map(Vec3::from)
            .collect();
        match &mut self.surface {
            Some(surface) => surface.update(&vertices, &vec![Vec3::zeros(); vertices.len()]),
            None => self.surface = Some(MeshSurface::new("posed body", &vertices, model.faces())?),
        }
        Ok(self.surface.as_ref().expect("set above"))
    }
}

/// Per point (world, m; a frame's skinned base): the offset to the nearest point of `body`
/// (the same frame's posed body) and that point's outward normal, both turned into
/// `canonical` (m; unit).
pub fn nearest_body(
    points: &[[f64; 3]],
    canonical: &Canonical,
    body: &MeshSurface,
) -> [Vec<[f64; 3]>; 2] {
    let (offsets, normals) = points
        .iter()
        .map(|&p| match body.query(Vec3::from(p), f64::INFINITY) {
            // The closest point is p - distance * normal (distance signed, negative inside).
            Some(found) => {
                let n: [f64; 3] = found.normal.into();
                let offset = n.map(|c| -found.distance * c);
                (
                    canonical.direction_to_canonical(offset),
                    canonical.direction_to_canonical(n),
                )
            }
            None => ([0.0; 3], [0.0; 3]),
        })
        .unzip();
    [offsets, normals]
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::geometry::RootRemoval;
    use motions::canonical_a_pose;

    /// On the posed body's own vertices every offset is zero. Moved 5 mm out along the
    /// body's normal, every offset is at most 5 mm long, ends on the body surface, and runs
    /// along the normal (against it outside the body, with it inside: a fold's far side);
    /// the normal is the body's own where the nearest point is the vertex it left.
    #[test]
    fn offsets_end_on_the_body_along_its_normal() {
        let model = BodyModel::default_body();
        let mut pose = canonical_a_pose();
        pose[1] = 0.6;
        pose[3 * 18] = 0.4;
        let frame = motions::FramePose {
            pose,
            transl: [0.2, 0.0, -0.5],
        };
        let betas = [0.3, -0.5];
        let body = FrameBody {
            pose: &frame,
            betas: &betas,
        };
        let mut surface = PosedSurface::default();
        let posed = surface.at(&model, body).unwrap();
        let canonical = Canonical::new(
            RootRemoval::Heading,
            [0.0, 0.6, 0.0],
            [0.2, 0.9, -0.5],
            [0.0, 0.9, 0.0],
        );
        let sample: Vec<usize> = (0..posed.num_vertices()).step_by(97).collect();
        for out in [0.0, 0.005] {
            let points: Vec<[f64; 3]> = sample
                .iter()
                .map(|&v| (posed.vertex(v) + posed.vertex_normal(v) * out).into())
                .collect();
            let [offsets, normals] = nearest_body(&points, &canonical, posed);
            let mut agree = 0;
            for (i, &v) in sample.iter().enumerate() {
                let length = offsets[i].iter().map(|c| c * c).sum::<f64>().sqrt();
                assert!(length <= out + 1e-4, "vertex {v}: |offset| {length}");
                // Back in the world: the offset's end is on the surface.
                let start = canonical.to_canonical(points[i]);
                let end = Vec3::from(
                    canonical.to_world(std::array::from_fn(|k| start[k] + offsets[i][k])),
                );
                let on = posed.query(end, 0.01).map(|f| f.distance.abs());
                assert!(
                    on.is_some_and(|d| d < 1e-4),
                    "vertex {v}: end {on:?} off the body"
                );
                let back: f64 = (0..3).map(|k| offsets[i][k] * normals[i][k]).sum();
                assert!(
                    (back.abs() - length).abs() < 1e-9,
                    "vertex {v}: offset . normal {back}"
                );
                let n = canonical.direction_to_canonical(posed.vertex_normal(v).into());
                let along: f64 = (0..3).map(|k| normals[i][k] * n[k]).sum();
                if out == 0.0 || length > 0.8 * out && along > 0.9 {
                    agree += 1;
                }
            }
            assert!(
                agree * 4 >= sample.len() * 3,
                "{agree} of {} agree",
                sample.len()
            );
        }
    }
}
