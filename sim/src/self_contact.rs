//! Cloth-cloth contact: which vertices are about to touch a triangle of the same cloth, and
//! the frictional node-pair constraints they become.
//!
//! Detection runs once per step. A bounding volume hierarchy (parry3d's `Bvh`, refitted every
//! step and rebuilt every [`REBUILD_STEPS`] steps) holds every triangle's box over its start
//! and predicted positions, widened by the detection band; every vertex's box over its own
//! start and predicted positions is queried against it. A candidate (vertex p, triangle t) is
//! kept when p is neither a corner of t nor a neighbour (by an edge or a seam) of one, p lies
//! over t or at most the kept distance beside it (so layers meeting edge to edge, as at a
//! folded strip's sides, are held too), and p is, or is predicted to come, closer to t's
//! plane than the band.
//!
//! A kept pair constrains the relative velocity of p and of its closest point on t,
//! (v_p - sum_i w_i v_i).n >= g, so that the gap along t's normal at the end of the step is at
//! least [`SolverParams::self_contact_distance`]; the solver treats it like a body contact
//! whose obstacle is that point (see `Solver::self_contact_step`).

use parry3d::bounding_volume::Aabb;
use parry3d::partitioning::{Bvh, BvhBuildStrategy, BvhLeafUpdateStatus, BvhWorkspace};
use rayon::prelude::*;

use crate::cloth::{Vec3, closest_on_triangle, to_parry};
use crate::params::SolverParams;

/// Steps between full rebuilds of the hierarchy (refits in between keep it valid but let its
/// boxes grow looser as the cloth deforms).
const REBUILD_STEPS: usize = 30;

/// The boxes cover at most this many kept distances of a vertex's predicted motion: a vertex
/// flying faster (a step about to blow up and be retried) is not worth a box across the whole
/// garment, which would make detection quadratic (measured: 270 s instead of 4 s of a
/// 180-frame run).
const MAX_SWEEP_FACTOR: f64 = 10.0;

/// Most pairs a vertex keeps (the closest): a vertex between two layers needs two or three,
/// and the cap bounds the work and memory when a blown-up step makes every box huge.
const MAX_PAIRS_PER_VERTEX: usize = 8;

/// The detection band is this many times the kept distance: pairs a little farther apart are
/// solved too (they take off at once when they are not approaching).
const BAND_FACTOR: f64 = 2.0;

/// One cloth vertex against one triangle of the same cloth.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct SelfContact {
    /// The vertex.
    pub vertex: u32,
    /// The triangle (index in the mesh).
    pub face: u32,
    /// The triangle's corners.
    pub triangle: [u32; 3],
    /// Barycentric weights of the point of the triangle below the vertex.
    pub weights: [f64; 3],
    /// Unit normal of the triangle, on the vertex's side.
    pub normal: Vec3,
    /// Lower bound g on the relative normal velocity, m/s.
    pub min_normal_velocity: f64,
    /// Coulomb friction coefficient between the layers.
    pub friction: f64,
    /// Gap along the normal at the start of the step, m (negative: the vertex is on the
    /// wrong side of a layer it was on the other side of).
    pub distance: f64,
    /// For a vertex over the triangle (normal = face normal): whether it is on the side the
    /// face normal points to; `None` for a vertex beside it.
    pub face_side: Option<bool>,
}

impl SelfContact {
    /// The pair's point on its triangle, taken from per-vertex values `q` (positions or
    /// velocities).
    pub fn point(&self, q: &[Vec3]) -> Vec3 {
        weighted(&self.triangle, &self.weights, q)
    }
}

fn weighted(triangle: &[u32; 3], weights: &[f64; 3], q: &[Vec3]) -> Vec3 {
    triangle
        .iter()
        .zip(weights)
        .map(|(&i, &w)| w * q[i as usize])
        .sum()
}

/// Lower bound on the relative normal velocity that leaves a pair `distance` apart now at
/// least the kept distance apart after a step of `h`, never pushing apart faster than
/// `max_push_out_speed`.
fn min_normal_velocity(distance: f64, h: f64, params: &SolverParams) -> f64 {
    ((params.self_contact_distance - distance) / h).min(params.max_push_out_speed)
}

/// Finds self-contacts of one cloth mesh, step after step.
pub(crate) struct SelfContactDetector {
    triangles: Vec<[u32; 3]>,
    /// The triangles each vertex may not touch (its own, and those of every vertex an edge
    /// or a seam joins it to), sorted, as compressed rows: one search per box hit, where 96%
    /// of the hits are such triangles.
    excluded_ptr: Vec<usize>,
    excluded: Vec<u32>,
    /// Each triangle's box as a leaf update of the hierarchy.
    boxes: Vec<(Aabb, u32, f32)>,
    statuses: Vec<BvhLeafUpdateStatus>,
    vertex_boxes: Vec<(Vec3, Vec3)>,
    bvh: Option<Bvh>,
    workspace: BvhWorkspace,
    steps_since_build: usize,
    /// (vertex << 32 | face, on the face normal's side) of the last step's layer pairs,
    /// sorted: the side a tracked pair must stay on.
    sides: Vec<(u64, bool)>,
    next_sides: Vec<(u64, bool)>,
}

impl SelfContactDetector {
    /// A detector for `triangles` over `num_vertices` vertices joined by mesh `edges` and
    /// `seams`. Vertices a seam joins act as one: neither they nor the vertices an edge joins
    /// to any of them touch each other's triangles. Without that, a seam's two sides push the
    /// triangles across it apart and the seam opens (2 mm on dress_tshirt's shoulders).
    pub fn new(
        num_vertices: usize,
        triangles: &[[u32; 3]],
        edges: &[[u32; 2]],
        seams: &[[u32; 2]],
    ) -> Self {
        let root = garments::joined_roots(num_vertices, seams);
        let mut members = vec![Vec::new(); num_vertices];
        for (v, &r) in root.iter().enumerate() {
            members[r as usize].push(v as u32);
        }
        let mut adjacency = vec![Vec::new(); num_vertices];
        for &[a, b] in edges.iter().chain(seams) {
            for &x in &members[root[a as usize] as usize] {
                for &y in &members[root[b as usize] as usize] {
                    if x != y {
                        adjacency[x as usize].push(y);
                        adjacency[y as usize].push(x);
                    }
                }
            }
        }
        // Vertex p may not touch triangle t when a corner of t is p or joined to p.
        let mut excluded_lists = vec![Vec::new(); num_vertices];
        for (t, corners) in triangles.iter().enumerate() {
            for &c in corners {
                excluded_lists[c as usize].push(t as u32);
                for &n in &adjacency[c as usize] {
                    excluded_lists[n as usize].push(t as u32);
                }
            }
        }
        let mut excluded_ptr = Vec::with_capacity(num_vertices + 1);
        let mut excluded = Vec::new();
        excluded_ptr.push(0);
        for mut list in excluded_lists {
            list.sort_unstable();
            list.dedup();
            excluded.extend(list);
            excluded_ptr.push(excluded.len());
        }
        Self {
            triangles: triangles.to_vec(),
            excluded_ptr,
            excluded,
            boxes: Vec::with_capacity(triangles.len()),
            statuses: Vec::new(),
            vertex_boxes: Vec::with_capacity(num_vertices),
            bvh: None,
            workspace: BvhWorkspace::default(),
            steps_since_build: 0,
            sides: Vec::new(),
            next_sides: Vec::new(),
        }
    }

    /// Whether vertex `p` is a corner of triangle `t` or joined to one by an edge or a seam.
    fn excluded(&self, p: u32, t: u32) -> bool {
        let p = p as usize;
        self.excluded[self.excluded_ptr[p]..self.excluded_ptr[p + 1]]
            .binary_search(&t)
            .is_ok()
    }

    /// Replaces `out` with the self-contacts of a step of length `h` from `positions` to
    /// `predicted` (x + h v*). Contacts come in vertex order.
    pub fn detect(
        &mut self,
        positions: &[Vec3],
        predicted: &[Vec3],
        h: f64,
        params: &SolverParams,
        out: &mut Vec<SelfContact>,
    ) {
        out.clear();
        let band = BAND_FACTOR * params.self_contact_distance;
        let max_sweep = MAX_SWEEP_FACTOR * params.self_contact_distance;
        // Each vertex's box over its start and (capped) predicted position, once.
        self.vertex_boxes.clear();
        self.vertex_boxes
            .par_extend(positions.par_iter().zip(predicted).map(|(x, p)| {
                let motion = p - x;
                let length = motion.norm();
                let end = if length > max_sweep {
                    x + motion * (max_sweep / length)
                } else {
                    *p
                };
                (x.inf(&end), x.sup(&end))
            }));
        let vertex_boxes = &self.vertex_boxes;
        let widen = Vec3::repeat(band);
        self.boxes.clear();
        self.boxes
            .par_extend(self.triangles.par_iter().enumerate().map(|(k, t)| {
                let [a, b, c] = t.map(|i| vertex_boxes[i as usize]);
                let lo = a.0.inf(&b.0).inf(&c.0) - widen;
                let hi = a.1.sup(&b.1).sup(&c.1) + widen;
                (Aabb::new(to_parry(&lo), to_parry(&hi)), k as u32, 0.0)
            }));
        match &mut self.bvh {
            Some(bvh) if self.steps_since_build < REBUILD_STEPS => {
                bvh.insert_or_update_batch_partially_parallel(&self.boxes, &mut self.statuses);
                bvh.refit_parallel(&mut self.workspace);
                self.steps_since_build += 1;
            }
            _ => {
                let leaves: Vec<Aabb> = self.boxes.iter().map(|b| b.0).collect();
                self.bvh = Some(Bvh::from_leaves(BvhBuildStrategy::Binned, &leaves));
                self.steps_since_build = 0;
            }
        }
        let bvh = self.bvh.as_ref().expect("hierarchy built above");
        let this = &*self;
        let found: Vec<Vec<SelfContact>> = (0..positions.len())
            .into_par_iter()
            .with_min_len(256)
            .map(|p| {
                let (lo, hi) = this.vertex_boxes[p];
                let query = Aabb::new(to_parry(&lo), to_parry(&hi));
                let mut mine: Vec<SelfContact> = Vec::new();
                for t in bvh.intersect_aabb(&query) {
                    if this.excluded(p as u32, t) {
                        continue;
                    }
                    let triangle = this.triangles[t as usize];
                    let Some(c) =
                        pair(p as u32, t, triangle, positions, predicted, h, band, params)
                    else {
                        continue;
                    };
                    // A closest point on an edge or corner is found once per triangle
                    // around it: keep one.
                    let duplicate = mine.iter().any(|d| {
                        (d.normal - c.normal).norm_squared() < 1e-18
                            && (d.distance - c.distance).abs() < 1e-12
                    });
                    if !duplicate {
                        mine.push(c);
                    }
                }
                if mine.len() > MAX_PAIRS_PER_VERTEX {
                    mine.sort_by(|a, b| a.distance.total_cmp(&b.distance));
                    mine.truncate(MAX_PAIRS_PER_VERTEX);
                }
                mine.sort_by_key(|c| c.face);
                mine
            })
            .collect();
        out.extend(found.into_iter().flatten());
        self.keep_sides(out, h, params);
    }

    /// A pair tracked since the last step stays on the side it was on: a vertex that the
    /// unconverged iteration let through its triangle is pushed back, instead of being held
    /// on the wrong side (which would also drag its neighbours through). Pairs seen for the
    /// first time take the side they are on.
    fn keep_sides(&mut self, contacts: &mut [SelfContact], h: f64, params: &SolverParams) {
        self.next_sides.clear();
        for c in contacts.iter_mut() {
            let Some(face_side) = c.face_side else {
                continue;
            };
            let key = (c.vertex as u64) << 32 | c.face as u64;
            let side = match self.sides.binary_search_by_key(&key, |e| e.0) {
                Ok(k) => self.sides[k].1,
                Err(_) => face_side,
            };
            if side != face_side {
                c.normal = -c.normal;
                c.distance = -c.distance;
                c.min_normal_velocity = min_normal_velocity(c.distance, h, params);
            }
            self.next_sides.push((key, side));
        }
        std::mem::swap(&mut self.sides, &mut self.next_sides);
    }
}

/// The constraint of vertex `p` against `triangle`, if `p` is (or is predicted to come)
/// within `band` of the triangle's closest point.
#[allow(clippy::too_many_arguments)]
fn pair(
    p: u32,
    face: u32,
    triangle: [u32; 3],
    positions: &[Vec3],
    predicted: &[Vec3],
    h: f64,
    band: f64,
    params: &SolverParams,
) -> Option<SelfContact> {
    let [a, b, c] = triangle.map(|i| positions[i as usize]);
    let x = positions[p as usize];
    let (closest, weights) = closest_on_triangle(x, a, b, c);
    // The normal is the face normal on the vertex's side, also for a vertex a little beside
    // the triangle (layers meeting edge to edge, as at a folded strip's sides): a normal
    // from the closest edge to the vertex would tilt and, linearized, brake a layer sliding
    // over an edge.
    let normal = (b - a).cross(&(c - a)).try_normalize(1e-30)?;
    let offset = x - closest;
    let along = offset.dot(&normal);
    let aside = (offset - along * normal).norm();
    let (normal, distance, face_side) = if aside <= along.abs() {
        let side = along >= 0.0;
        (if side { normal } else { -normal }, along.abs(), Some(side))
    } else {
        (offset / offset.norm(), offset.norm(), None)
    };
    let predicted_gap =
        (predicted[p as usize] - weighted(&triangle, &weights, predicted)).dot(&normal);
    if distance.min(predicted_gap) >= band {
        return None;
    }
    Some(SelfContact {
        vertex: p,
        face,
        triangle,
        weights,
        normal,
        min_normal_velocity: min_normal_velocity(distance, h, params),
        friction: params.self_friction,
        distance,
        face_side,
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::cloth::ClothMesh;

    fn params() -> SolverParams {
        SolverParams {
            self_contact: true,
            ..SolverParams::default()
        }
    }

    /// Two 5x5 sheets of 10 cm, the second `gap` above the first.
    fn two_sheets(gap: f64) -> (Vec<Vec3>, Vec<[u32; 3]>, Vec<[u32; 2]>) {
        let lower = ClothMesh::grid(5, 0.1, 0.0).unwrap();
        let mut positions = lower.rest().to_vec();
        positions.extend(lower.rest().iter().map(|p| p + Vec3::new(0.0, gap, 0.0)));
        let n = lower.num_vertices() as u32;
        let mut triangles = lower.triangles().to_vec();
        triangles.extend(lower.triangles().iter().map(|t| t.map(|i| i + n)));
        let mut edges = lower.edges().to_vec();
        edges.extend(lower.edges().iter().map(|e| e.map(|i| i + n)));
        (positions, triangles, edges)
    }

    #[test]
    fn layers_closer_than_the_band_touch_and_a_flat_sheet_does_not() {
        let params = params();
        let (positions, triangles, edges) = two_sheets(0.005);
        let mut detector = SelfContactDetector::new(positions.len(), &triangles, &edges, &[]);
        let mut out = Vec::new();
        detector.detect(&positions, &positions, 0.01, &params, &mut out);
        // Every vertex of each sheet is over (or on the edge of) the other sheet.
        let vertices: std::collections::BTreeSet<u32> = out.iter().map(|c| c.vertex).collect();
        assert_eq!(vertices.len(), 50, "{out:?}");
        for c in &out {
            assert!((c.distance - 0.005).abs() < 1e-12);
            let upper = c.vertex >= 25;
            assert_eq!(c.normal.y > 0.0, upper, "normal points to the vertex");
            assert!(c.triangle.iter().all(|&i| (i >= 25) != upper));
            // Gap 5 mm, kept 4 mm: may approach by 1 mm in the step.
            let expected = (params.self_contact_distance - 0.005) / 0.01;
            assert!((c.min_normal_velocity - expected).abs() < 1e-12);
        }
        // Far apart: nothing; one sheet alone: nothing (neighbours excluded).
        let (positions, ..) = two_sheets(0.05);
        detector.detect(&positions, &positions, 0.01, &params, &mut out);
        assert!(out.is_empty());
    }

    #[test]
    fn a_vertex_predicted_to_cross_is_caught() {
        let params = params();
        let (positions, triangles, edges) = two_sheets(0.03);
        let mut predicted = positions.clone();
        // The upper sheet is predicted to fall 3.5 cm, through the lower one.
        for p in &mut predicted[25..] {
            p.y -= 0.035;
        }
        let mut detector = SelfContactDetector::new(positions.len(), &triangles, &edges, &[]);
        let mut out = Vec::new();
        detector.detect(&positions, &predicted, 0.01, &params, &mut out);
        assert!(out.iter().any(|c| c.vertex >= 25 && c.normal.y > 0.0));
        // Refitted on the next step, the sheets now 6 mm apart and still: found; 3 cm apart
        // and still: nothing.
        let (close, ..) = two_sheets(0.006);
        detector.detect(&close, &close, 0.01, &params, &mut out);
        let vertices: std::collections::BTreeSet<u32> = out.iter().map(|c| c.vertex).collect();
        assert_eq!(vertices.len(), 50);
        detector.detect(&positions, &positions, 0.01, &params, &mut out);
        assert!(out.is_empty());
    }

    #[test]
    fn neighbours_and_seams_are_excluded() {
        // Two layers 2 mm apart touch; once seams join each vertex to the one above it, every
        // vertex projects onto a corner it is linked to and nothing is left.
        let (positions, triangles, edges) = two_sheets(0.002);
        let mut detector = SelfContactDetector::new(positions.len(), &triangles, &edges, &[]);
        let mut out = Vec::new();
        detector.detect(&positions, &positions, 0.01, &params(), &mut out);
        assert!(!out.is_empty());
        let seams: Vec<[u32; 2]> = (0..25).map(|i| [i, i + 25]).collect();
        let mut detector = SelfContactDetector::new(positions.len(), &triangles, &edges, &seams);
        detector.detect(&positions, &positions, 0.01, &params(), &mut out);
        assert!(out.is_empty(), "{out:?}");
    }

    #[test]
    fn vertices_a_seam_joins_share_their_neighbours() {
        // One seam joins corner 0 to corner 25 above it. Vertex 26, an edge away from 25,
        // lies over the edge 0-1: taken as a plain link it touches a triangle of vertex 0;
        // taken as a seam, 0 and 25 act as one vertex and 26 is its neighbour.
        let (positions, triangles, edges) = two_sheets(0.002);
        let touches_corner = |out: &[SelfContact]| {
            out.iter()
                .any(|c| c.vertex == 26 && c.triangle.contains(&0))
        };
        let mut out = Vec::new();
        let mut linked = edges.clone();
        linked.push([0, 25]);
        let mut detector = SelfContactDetector::new(positions.len(), &triangles, &linked, &[]);
        detector.detect(&positions, &positions, 0.01, &params(), &mut out);
        assert!(touches_corner(&out), "{out:?}");
        let mut detector =
            SelfContactDetector::new(positions.len(), &triangles, &edges, &[[0, 25]]);
        detector.detect(&positions, &positions, 0.01, &params(), &mut out);
        assert!(!out.is_empty());
        assert!(!touches_corner(&out), "{out:?}");
    }
}
