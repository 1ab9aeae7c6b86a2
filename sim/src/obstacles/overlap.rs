//! Cloth caught where the posed body overlaps itself. Skinning lets body parts press into
//! each other (an arm into the torso at the armpit, thigh into thigh); between two such parts
//! no position is outside both, so cloth caught there is inside the body however well contact
//! is solved, and keeping it out would need the body's own contact resolved first. The
//! penetration figures therefore count such cloth vertices apart from the rest
//! (docs/PHYSICS.md, Body overlaps).
//!
//! A body vertex is *buried* when a point just outside it, along its normal, is inside the
//! body: another part covers it. A cloth vertex inside the body is *in an overlap* when it is
//! inside two parts at once (winding number 2 or more) or a buried body vertex lies within
//! [`OVERLAP_REACH_M`] of it.

use super::trimesh::MeshSurface;
use crate::cloth::Vec3;

/// How near a buried body vertex must be for a cloth vertex inside the body to count as
/// caught in the body's overlap, m: about two body edge lengths, the scale of an overlap's rim
/// (docs/BENCHMARKS.md, shard 0/20 at 10 mm).
pub const OVERLAP_REACH_M: f64 = 0.03;

/// How far outside a body vertex, along its normal, the burial test looks, m: far enough to
/// leave the vertex's own surface in f32, near enough to stay within a crease.
const BURIAL_OFFSET_M: f64 = 1e-3;

/// Cloth vertices inside the body, split by whether the body overlaps itself there.
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub struct Penetration {
    /// Deepest vertex inside the body away from any overlap, m (0 if none).
    pub depth_m: f64,
    /// Vertices inside the body away from any overlap.
    pub inside: usize,
    /// Deepest vertex inside the body in an overlap, m (0 if none).
    pub overlap_depth_m: f64,
    /// Vertices inside the body in an overlap.
    pub overlap_inside: usize,
}

impl Penetration {
    /// The larger of each figure (a run's worst frame).
    pub fn max(self, other: Penetration) -> Penetration {
        Penetration {
            depth_m: self.depth_m.max(other.depth_m),
            inside: self.inside.max(other.inside),
            overlap_depth_m: self.overlap_depth_m.max(other.overlap_depth_m),
            overlap_inside: self.overlap_inside.max(other.overlap_inside),
        }
    }
}

/// Splits the points inside `body` (negative `distances`, signed distances to it) by whether
/// the body overlaps itself there. Cost: a scan of the body's vertices per point inside, and
/// one winding number per body vertex within reach of one (remembered for the call).
pub fn split_penetration(body: &MeshSurface, points: &[Vec3], distances: &[f64]) -> Penetration {
    let mut burial = vec![Burial::Unknown; body.num_vertices()];
    let mut result = Penetration::default();
    for (&p, &d) in points.iter().zip(distances) {
        if d >= 0.0 {
            continue;
        }
        if in_overlap(body, p, &mut burial) {
            result.overlap_inside += 1;
            result.overlap_depth_m = result.overlap_depth_m.max(-d);
        } else {
            result.inside += 1;
            result.depth_m = result.depth_m.max(-d);
        }
    }
    result
}

#[derive(Debug, Clone, Copy, PartialEq)]
enum Burial {
    Unknown,
    Clear,
    Buried,
}

fn in_overlap(body: &MeshSurface, p: Vec3, burial: &mut [Burial]) -> bool {
    if body.winding_number(p) >= 2 {
        return true;
    }
    let reach = OVERLAP_REACH_M * OVERLAP_REACH_M;
    (0..body.num_vertices()).any(|v| {
        let x = body.vertex(v);
        if (x - p).norm_squared() > reach {
            return false;
        }
        if burial[v] == Burial::Unknown {
            let outside = x + body.vertex_normal(v) * BURIAL_OFFSET_M;
            burial[v] = if body.winding_number(outside) > 0 {
                Burial::Buried
            } else {
                Burial::Clear
            };
        }
        burial[v] == Burial::Buried
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A closed axis-aligned box as 12 outward triangles, vertices offset by `first`.
    fn cuboid(lo: Vec3, hi: Vec3, first: u32) -> (Vec<Vec3>, Vec<[u32; 3]>) {
        let v = (0..8)
            .map(|k| {
                Vec3::new(
                    if k & 1 == 0 { lo.x } else { hi.x },
                    if k & 2 == 0 { lo.y } else { hi.y },
                    if k & 4 == 0 { lo.z } else { hi.z },
                )
            })
            .collect();
        let quads = [
            [0, 2, 3, 1],
            [4, 5, 7, 6],
            [0, 1, 5, 4],
            [2, 6, 7, 3],
            [0, 4, 6, 2],
            [1, 3, 7, 5],
        ];
        let f = quads
            .iter()
            .flat_map(|q| [[q[0], q[1], q[2]], [q[0], q[2], q[3]]])
            .map(|t: [u32; 3]| t.map(|i| i + first))
            .collect();
        (v, f)
    }

    /// Two boxes, the second (10 cm) pressed 2 cm into the first (20 cm): one body whose parts
    /// overlap, as a posed arm overlaps the torso.
    fn overlapping_parts() -> MeshSurface {
        let (mut v, mut f) = cuboid(Vec3::zeros(), Vec3::new(0.2, 0.2, 0.2), 0);
        let (v2, f2) = cuboid(Vec3::new(0.18, 0.05, 0.05), Vec3::new(0.28, 0.15, 0.15), 8);
        v.extend(v2);
        f.extend(f2);
        MeshSurface::new("parts", &v, &f).unwrap()
    }

    fn split(body: &MeshSurface, points: &[Vec3]) -> Penetration {
        let distances: Vec<f64> = points
            .iter()
            .map(|&p| body.query(p, f64::INFINITY).unwrap().distance)
            .collect();
        split_penetration(body, points, &distances)
    }

    #[test]
    fn buried_corners_mark_the_overlap_and_nothing_else() {
        let body = overlapping_parts();
        // The small box's four corners at x = 0.18 lie inside the big box.
        let buried: Vec<usize> = (0..body.num_vertices())
            .filter(|&v| {
                let outside = body.vertex(v) + body.vertex_normal(v) * BURIAL_OFFSET_M;
                body.winding_number(outside) > 0
            })
            .collect();
        assert_eq!(buried, vec![8, 10, 12, 14]);
    }

    #[test]
    fn inside_points_are_split_by_the_overlap() {
        let body = overlapping_parts();
        let points = [
            // Inside both parts (winding number 2), 1 cm deep in the small box's end.
            Vec3::new(0.19, 0.1, 0.1),
            // Inside the big box only, 1 cm deep, 2.4 cm from the buried corner
            // (0.18, 0.05, 0.05).
            Vec3::new(0.19, 0.03, 0.06),
            // Inside the big box far from the overlap, 5 mm deep.
            Vec3::new(0.1, 0.005, 0.1),
            // Inside the small box only, near its free end, 5 mm deep, 10 cm from any
            // buried corner.
            Vec3::new(0.275, 0.1, 0.1),
            // Outside.
            Vec3::new(0.1, -0.05, 0.1),
        ];
        let result = split(&body, &points);
        assert_eq!(result.overlap_inside, 2, "{result:?}");
        assert_eq!(result.inside, 2, "{result:?}");
        assert!((result.depth_m - 0.005).abs() < 1e-6, "{result:?}");
        assert!((result.overlap_depth_m - 0.01).abs() < 1e-6, "{result:?}");
    }

    #[test]
    fn a_body_without_overlaps_counts_every_point_as_clear() {
        let (v, f) = cuboid(Vec3::zeros(), Vec3::new(0.2, 0.2, 0.2), 0);
        let body = MeshSurface::new("box", &v, &f).unwrap();
        let points = [Vec3::new(0.1, 0.1, 0.01), Vec3::new(0.005, 0.1, 0.1)];
        let result = split(&body, &points);
        assert_eq!((result.inside, result.overlap_inside), (2, 0));
        assert!((result.depth_m - 0.01).abs() < 1e-6);
    }
}
