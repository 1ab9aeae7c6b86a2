//! Triangle-mesh obstacles on parry3d's BVH: closest-point queries on the mesh's triangles
//! with the inside test from angle-weighted pseudo-normals (a closed, consistently oriented
//! mesh), refit in place when the mesh moves. parry3d works in f32; positions are converted at
//! the boundary (1e-7 m is far below any contact tolerance).
//!
//! Written over parry's `Bvh` and `Triangle` rather than its `TriMesh` (which the engine used
//! until 2026-12-02) for two reasons, both measured on the default skirt's walk: `TriMesh`
//! recomputes every pseudo-normal at each refit, serially, through hash maps (2.7 s of a 12 s
//! run, a refit per substep), where a query needs only the one of the feature it lands on; and
//! a moving body's BVH can be fitted once per frame around its triangles swept between two
//! keyframes ([`MeshSurface::sweep`]), any pose in between then being queried exactly.

use std::collections::HashMap;

use parry3d::bounding_volume::Aabb;
use parry3d::math::Vector;
use parry3d::partitioning::{Bvh, BvhBuildStrategy, BvhLeafUpdateStatus, BvhNode, BvhWorkspace};
use parry3d::query::{PointQuery, PointQueryWithLocation, Ray};
use parry3d::shape::{Triangle, TrianglePointLocation};
use rayon::prelude::*;

use super::{Obstacle, SurfacePoint};
use crate::cloth::{Vec3, to_parry};
use crate::error::{Error, Result};

fn from_parry(p: Vector) -> Vec3 {
    Vec3::new(p.x as f64, p.y as f64, p.z as f64)
}

/// A closed triangle mesh with per-vertex velocities, queried for signed distances (the
/// engine's body and props, and the surrogate's intersection guidance).
pub struct MeshSurface {
    bvh: Bvh,
    workspace: BvhWorkspace,
    faces: Vec<[u32; 3]>,
    vertices: Vec<Vector>,
    velocities: Vec<Vec3>,
    /// The edge (index into `edge_ptr`) of each triangle's sides AB, BC and CA, parry's
    /// `TrianglePointLocation::OnEdge` numbering.
    face_edges: Vec<[u32; 3]>,
    /// Triangles of each edge (compressed rows).
    edge_ptr: Vec<u32>,
    edge_faces: Vec<u32>,
    /// Triangles around each vertex (compressed rows).
    ring_ptr: Vec<u32>,
    ring_faces: Vec<u32>,
    /// Scratch: each triangle's box at the last refit, as a leaf update.
    boxes: Vec<(Aabb, u32, f32)>,
    statuses: Vec<BvhLeafUpdateStatus>,
}

impl MeshSurface {
    /// A closed, outward-oriented mesh; `name` names it in errors.
    pub fn new(name: &str, vertices: &[Vec3], faces: &[[u32; 3]]) -> Result<Self> {
        let fail = |problem: String| Error::Obstacle {
            obstacle: name.to_string(),
            problem,
        };
        if let Some(i) = vertices
            .iter()
            .position(|p| !p.iter().all(|c| c.is_finite()))
        {
            return Err(fail(format!("vertex {i} is not finite")));
        }
        if faces
            .iter()
            .flatten()
            .any(|&v| v as usize >= vertices.len())
        {
            return Err(fail("a face refers to a missing vertex".into()));
        }
        if faces.is_empty() {
            return Err(fail("the mesh has no triangles".into()));
        }
        let open = motions::boundary_edges(faces);
        if open > 0 {
            return Err(fail(format!(
                "the mesh is not closed ({open} boundary edges); the inside test needs a closed, consistently oriented surface"
            )));
        }
        let (face_edges, edge_ptr, edge_faces) = edges(faces);
        let (ring_ptr, ring_faces) = rings(vertices.len(), faces);
        let mut surface = Self {
            bvh: Bvh::new(),
            workspace: BvhWorkspace::default(),
            faces: faces.to_vec(),
            vertices: vertices.iter().map(to_parry).collect(),
            velocities: vec![Vec3::zeros(); vertices.len()],
            face_edges,
            edge_ptr,
            edge_faces,
            ring_ptr,
            ring_faces,
            boxes: Vec::new(),
            statuses: Vec::new(),
        };
        surface.fit_boxes(None);
        let leaves: Vec<Aabb> = surface.boxes.iter().map(|b| b.0).collect();
        surface.bvh = Bvh::from_leaves(BvhBuildStrategy::Binned, &leaves);
        Ok(surface)
    }

    /// Vertices of the mesh.
    pub fn num_vertices(&self) -> usize {
        self.velocities.len()
    }

    /// Moves the vertices (refits the BVH) and sets their velocities.
    pub fn update(&mut self, vertices: &[Vec3], velocities: &[Vec3]) {
        self.place(vertices);
        self.velocities.copy_from_slice(velocities);
        self.fit_boxes(None);
        self.refit();
    }

    /// Fits the BVH around every triangle swept linearly from `start` to `end`, places the
    /// mesh at `start` and sets the velocities: until the next refit, [`Self::place`] may put
    /// the mesh at any pose (1 - a) start + a end, a in [0, 1], without refitting.
    pub fn sweep(&mut self, start: &[Vec3], end: &[Vec3], velocities: &[Vec3]) {
        let end: Vec<Vector> = end.par_iter().map(to_parry).collect();
        self.place(start);
        self.velocities.copy_from_slice(velocities);
        self.fit_boxes(Some(&end));
        self.refit();
    }

    /// Moves the vertices without refitting: only for poses inside the last [`Self::sweep`].
    pub fn place(&mut self, vertices: &[Vec3]) {
        self.vertices
            .par_iter_mut()
            .zip(vertices)
            .for_each(|(v, p)| *v = to_parry(p));
    }

    /// Each triangle's box at the current vertices (and at `other`, when sweeping), as BVH
    /// leaf updates.
    fn fit_boxes(&mut self, other: Option<&[Vector]>) {
        let vertices = &self.vertices;
        self.boxes.clear();
        self.boxes
            .par_extend(self.faces.par_iter().enumerate().map(|(t, f)| {
                let [a, b, c] = f.map(|i| vertices[i as usize]);
                let mut lo = a.min(b).min(c);
                let mut hi = a.max(b).max(c);
                if let Some(other) = other {
                    let [a, b, c] = f.map(|i| other[i as usize]);
                    lo = lo.min(a.min(b).min(c));
                    hi = hi.max(a.max(b).max(c));
                }
                (Aabb::new(lo, hi), t as u32, 0.0)
            }));
    }

    fn refit(&mut self) {
        self.bvh
            .insert_or_update_batch_partially_parallel(&self.boxes, &mut self.statuses);
        self.bvh.refit_parallel(&mut self.workspace);
    }

    fn triangle(&self, t: u32) -> Triangle {
        let [a, b, c] = self.faces[t as usize].map(|i| self.vertices[i as usize]);
        Triangle::new(a, b, c)
    }

    /// The outward pseudo-normal (not normalized) of the feature a projection landed on: the
    /// face's normal, the sum of an edge's face normals, or a vertex's angle-weighted sum
    /// (Baerentzen and Aanaes: the sign of (p - closest) . n is the side, on a closed mesh).
    fn pseudo_normal(&self, t: u32, location: &TrianglePointLocation) -> Vector {
        let unit = |f: u32| self.triangle(f).normal().unwrap_or(Vector::ZERO);
        match *location {
            TrianglePointLocation::OnFace(..) | TrianglePointLocation::OnSolid => {
                self.triangle(t).scaled_normal()
            }
            TrianglePointLocation::OnEdge(i, _) => {
                let e = self.face_edges[t as usize][i as usize] as usize;
                let faces =
                    &self.edge_faces[self.edge_ptr[e] as usize..self.edge_ptr[e + 1] as usize];
                faces.iter().map(|&f| unit(f)).sum()
            }
            TrianglePointLocation::OnVertex(i) => {
                self.vertex_pseudo_normal(self.faces[t as usize][i as usize])
            }
        }
    }

    /// A vertex's angle-weighted sum of its triangles' unit normals (not normalized).
    fn vertex_pseudo_normal(&self, v: u32) -> Vector {
        let unit = |f: u32| self.triangle(f).normal().unwrap_or(Vector::ZERO);
        let ring = &self.ring_faces
            [self.ring_ptr[v as usize] as usize..self.ring_ptr[v as usize + 1] as usize];
        ring.iter()
            .map(|&f| {
                let face = self.faces[f as usize];
                let k = face.iter().position(|&u| u == v).expect("ring of v");
                let p = |j: usize| self.vertices[face[(k + j) % 3] as usize];
                let angle = (p(1) - p(0)).angle_between(p(2) - p(0));
                unit(f) * angle
            })
            .sum()
    }

    /// Vertex `v`'s position, m.
    pub fn vertex(&self, v: usize) -> Vec3 {
        from_parry(self.vertices[v])
    }

    /// Vertex `v`'s outward unit normal (angle-weighted), or zero where its triangles cancel.
    pub fn vertex_normal(&self, v: usize) -> Vec3 {
        let n = from_parry(self.vertex_pseudo_normal(v as u32));
        let length = n.norm();
        if length > 0.0 { n / length } else { n }
    }

    /// The closest surface point if within `max_distance`, else `None` (whatever the side).
    pub fn query(&self, p: Vec3, max_distance: f64) -> Option<SurfacePoint> {
        let point = to_parry(&p);
        let max = if max_distance.is_finite() {
            max_distance as f32
        } else {
            f32::MAX
        };
        let (triangle, (_, (projection, location))) = self.bvh.find_best(
            max,
            |node: &BvhNode, _| node.aabb().distance_to_local_point(point, true),
            |t, _| {
                let found = self
                    .triangle(t)
                    .project_local_point_and_get_location(point, false);
                Some(((found.0.point - point).length(), found))
            },
        )?;
        let closest = from_parry(projection.point);
        let offset = p - closest;
        let length = offset.norm();
        // The pseudo-normal decides the side only where the mesh is a clean closed surface.
        // A posed body folds where skinning collapses it (an armpit, a hip fold): there a
        // triangle may face inward, and points outside the body in front of it read as
        // inside, 27 mm deep on a larger body's arm swing, which the contact solve then
        // pushes through the fold. Such an answer is confirmed by the winding number.
        let inside = (point - projection.point).dot(self.pseudo_normal(triangle, &location)) <= 0.0
            && self.winding_number(p) > 0;
        let sign = if inside { -1.0 } else { 1.0 };
        let face = self.faces[triangle as usize];
        let normal = if length > 1e-7 {
            offset * (sign / length)
        } else {
            from_parry(self.triangle(triangle).scaled_normal()).normalize()
        };
        let velocity = match location.barycentric_coordinates() {
            Some(b) => (0..3)
                .map(|k| self.velocities[face[k] as usize] * b[k] as f64)
                .sum(),
            None => Vec3::zeros(),
        };
        Some(SurfacePoint {
            distance: sign * length,
            normal,
            velocity,
        })
    }

    /// The winding number of the mesh around `p`: 1 inside a closed outward mesh, 0 outside,
    /// 2 where two parts of a self-intersecting one overlap, whatever inward-facing folds lie
    /// between. It is the signed count of a ray's crossings (+1 leaving through a face, -1
    /// entering). The ray leaves by the nearest side of the mesh's bounding box (a short ray
    /// meets few BVH nodes: a body is thinnest front to back). A ray passing within a hair of
    /// an edge or a vertex could count a crossing twice or not at all, so such a ray is
    /// replaced by the next nearest side's (the majority of the first three decides if all
    /// graze).
    pub fn winding_number(&self, p: Vec3) -> i32 {
        let aabb = self.bvh.root_aabb();
        let (lo, hi) = (from_parry(aabb.mins), from_parry(aabb.maxs));
        // Distance to each side (+x, -x, +y, ...), nearest first.
        let mut sides: [(f64, usize); 6] = std::array::from_fn(|k| {
            let gap = if k % 2 == 0 { hi - p } else { p - lo };
            (gap[k / 2], k)
        });
        sides.sort_by(|a, b| a.0.total_cmp(&b.0));
        let mut counts = [0; 3];
        for (n, &(_, k)) in sides.iter().enumerate() {
            let direction = Vec3::from(RAY_DIRECTIONS[k]);
            match self.crossings(p, direction) {
                (count, false) => return count,
                (count, true) if n < 3 => counts[n] = count,
                _ => {}
            }
        }
        match counts {
            [a, b, _] if a == b => a,
            [a, _, c] if a == c => a,
            [_, b, _] => b,
        }
    }

    /// The signed crossings of the ray (grazing ones counted as they fall), and whether it
    /// grazed an edge or a vertex.
    fn crossings(&self, origin: Vec3, direction: Vec3) -> (i32, bool) {
        let ray = Ray::new(to_parry(&origin), to_parry(&direction));
        self.bvh
            .leaves(|node: &BvhNode| node.cast_ray(&ray, f32::MAX) < f32::MAX)
            .fold((0, false), |(sum, grazed), t| {
                let [a, b, c] =
                    self.faces[t as usize].map(|i| from_parry(self.vertices[i as usize]));
                match ray_crossing(origin, direction, a, b, c) {
                    Some(crossing) => (sum + crossing, grazed),
                    None => (sum, true),
                }
            })
    }

    /// Whether `p` is within `margin` of the mesh's bounding box.
    pub fn near_bounds(&self, p: Vec3, margin: f64) -> bool {
        let aabb = self.bvh.root_aabb();
        let (lo, hi) = (from_parry(aabb.mins), from_parry(aabb.maxs));
        (0..3).all(|c| p[c] >= lo[c] - margin && p[c] <= hi[c] + margin)
    }
}

/// Directions of the winding number's rays, toward +x, -x, +y, -y, +z and -z, each tilted a
/// little off the axis so that no ray runs along a mesh's edges or faces by construction.
const RAY_DIRECTIONS: [[f64; 3]; 6] = [
    [0.998_2, 0.041_3, 0.043_1],
    [-0.997_9, 0.037_9, -0.052_3],
    [0.047_1, 0.998_1, 0.039_2],
    [-0.035_3, -0.998_3, 0.046_3],
    [0.044_7, 0.036_1, 0.998_3],
    [-0.039_7, 0.048_9, -0.998_0],
];

/// Barycentric margin (and relative determinant) under which a ray grazes a triangle's
/// boundary or runs along its plane.
const GRAZING: f64 = 1e-9;

/// +1 where the ray from `origin` along `direction` leaves through triangle (a, b, c) (the
/// direction along its normal), -1 where it enters, 0 where it misses (Moller-Trumbore);
/// `None` where it grazes the triangle's edges or corners or runs along its plane.
fn ray_crossing(origin: Vec3, direction: Vec3, a: Vec3, b: Vec3, c: Vec3) -> Option<i32> {
    let (ab, ac) = (b - a, c - a);
    let p = direction.cross(&ac);
    let det = ab.dot(&p);
    let scale = ab.norm() * ac.norm() * direction.norm();
    if det.abs() <= GRAZING * scale {
        // Along the plane (grazing), or a triangle without area (never crossed).
        return if scale > 0.0 { None } else { Some(0) };
    }
    let offset = origin - a;
    let u = offset.dot(&p) / det;
    let q = offset.cross(&ab);
    let v = direction.dot(&q) / det;
    let w = 1.0 - u - v;
    let t = ac.dot(&q) / det;
    if u < -GRAZING || v < -GRAZING || w < -GRAZING || t <= 0.0 {
        return Some(0);
    }
    if u < GRAZING || v < GRAZING || w < GRAZING {
        return None;
    }
    // det = -direction . (ab x ac): negative when the ray runs along the face's normal.
    Some(if det < 0.0 { 1 } else { -1 })
}

/// Each triangle's edges (AB, BC, CA) as edge indices, and each edge's triangles.
fn edges(faces: &[[u32; 3]]) -> (Vec<[u32; 3]>, Vec<u32>, Vec<u32>) {
    let mut index: HashMap<(u32, u32), u32> = HashMap::new();
    let face_edges: Vec<[u32; 3]> = faces
        .iter()
        .map(|f| {
            [0, 1, 2].map(|k| {
                let (a, b) = (f[k], f[(k + 1) % 3]);
                let next = index.len() as u32;
                *index.entry((a.min(b), a.max(b))).or_insert(next)
            })
        })
        .collect();
    let (ptr, members) = compressed_rows(
        index.len(),
        face_edges
            .iter()
            .enumerate()
            .flat_map(|(t, e)| e.map(|e| (e, t as u32))),
    );
    (face_edges, ptr, members)
}

/// Each vertex's triangles.
fn rings(vertices: usize, faces: &[[u32; 3]]) -> (Vec<u32>, Vec<u32>) {
    compressed_rows(
        vertices,
        faces
            .iter()
            .enumerate()
            .flat_map(|(t, f)| f.map(|v| (v, t as u32))),
    )
}

/// Rows of `(row, member)` pairs as offsets and members, members in the order given.
fn compressed_rows(
    rows: usize,
    pairs: impl Iterator<Item = (u32, u32)> + Clone,
) -> (Vec<u32>, Vec<u32>) {
    let mut ptr = vec![0u32; rows + 1];
    for (r, _) in pairs.clone() {
        ptr[r as usize + 1] += 1;
    }
    for r in 0..rows {
        ptr[r + 1] += ptr[r];
    }
    let mut fill = ptr.clone();
    let mut members = vec![0u32; ptr[rows] as usize];
    for (r, m) in pairs {
        members[fill[r as usize] as usize] = m;
        fill[r as usize] += 1;
    }
    (ptr, members)
}

/// A static closed mesh prop (a chair, a box from a file): for library users' scenes in
/// `Obstacles::props` (no command or scenario uses it yet); its tests are here.
pub struct StaticMesh {
    surface: MeshSurface,
    friction: f64,
}

impl StaticMesh {
    /// A closed, outward-oriented triangle mesh.
    pub fn new(vertices: &[Vec3], faces: &[[u32; 3]], friction: f64) -> Result<Self> {
        Ok(Self {
            surface: MeshSurface::new("static mesh", vertices, faces)?,
            friction,
        })
    }
}

impl Obstacle for StaticMesh {
    fn friction(&self) -> f64 {
        self.friction
    }
    fn advance(&mut self, _time: f64) {}
    fn surface_point(&self, p: Vec3, max_distance: f64) -> Option<SurfacePoint> {
        if !self.surface.near_bounds(p, max_distance) {
            return None;
        }
        // Bounded first; a miss inside the bounds may still be deep inside.
        self.surface.query(p, max_distance).or_else(|| {
            self.surface
                .query(p, f64::INFINITY)
                .filter(|s| s.distance < 0.0)
        })
    }
}

#[cfg(test)]
pub(crate) mod tests {
    use super::*;

    /// An axis-aligned unit cube as 12 outward triangles.
    pub(crate) fn cube() -> (Vec<Vec3>, Vec<[u32; 3]>) {
        let v: Vec<Vec3> = (0..8)
            .map(|i| Vec3::new((i & 1) as f64, ((i >> 1) & 1) as f64, ((i >> 2) & 1) as f64))
            .collect();
        let f = vec![
            [0, 2, 1],
            [1, 2, 3],
            [4, 5, 6],
            [5, 7, 6],
            [0, 1, 4],
            [1, 5, 4],
            [2, 6, 3],
            [3, 6, 7],
            [0, 4, 2],
            [2, 4, 6],
            [1, 3, 5],
            [3, 7, 5],
        ];
        (v, f)
    }

    /// Points on a grid around and through the unit cube, closest features being faces,
    /// edges and corners alike.
    fn probes() -> Vec<Vec3> {
        let steps = [
            -0.3, -0.05, 0.0, 0.02, 0.25, 0.5, 0.75, 0.98, 1.0, 1.05, 1.3,
        ];
        let mut out = Vec::new();
        for x in steps {
            for y in steps {
                for z in steps {
                    out.push(Vec3::new(x, y, z));
                }
            }
        }
        out
    }

    #[test]
    fn the_sign_is_the_side_on_faces_edges_and_corners() {
        let (v, f) = cube();
        let surface = MeshSurface::new("cube", &v, &f).unwrap();
        for p in probes() {
            let inside = p.iter().all(|&c| c > 0.0 && c < 1.0);
            let on_surface = p.iter().all(|&c| (0.0..=1.0).contains(&c))
                && p.iter().any(|&c| c == 0.0 || c == 1.0);
            let s = surface.query(p, f64::INFINITY).unwrap();
            if !on_surface {
                assert_eq!(s.distance < 0.0, inside, "{p:?}: {s:?}");
            }
            // The distance is the box's exact signed distance.
            let outside = p.map(|c| (-c).max(c - 1.0).max(0.0)).norm();
            let depth = p
                .iter()
                .map(|&c| c.min(1.0 - c))
                .fold(f64::INFINITY, f64::min);
            let exact = if inside { -depth } else { outside };
            assert!(
                (s.distance - exact).abs() < 1e-6,
                "{p:?}: {s:?} against {exact}"
            );
        }
    }

    /// Winding number by solid angles (Van Oosterom and Strackee), independent of the rays.
    fn solid_angle_winding(v: &[Vec3], f: &[[u32; 3]], p: Vec3) -> f64 {
        let total: f64 = f
            .iter()
            .map(|t| {
                let [a, b, c] = t.map(|i| v[i as usize] - p);
                let (la, lb, lc) = (a.norm(), b.norm(), c.norm());
                let det = a.dot(&b.cross(&c));
                let div = la * lb * lc + a.dot(&b) * lc + b.dot(&c) * la + c.dot(&a) * lb;
                2.0 * det.atan2(div)
            })
            .sum();
        total / (4.0 * std::f64::consts::PI)
    }

    /// The unit cube and a copy shifted by `shift`, as one self-intersecting mesh.
    fn two_cubes(shift: Vec3) -> (Vec<Vec3>, Vec<[u32; 3]>) {
        let (mut v, mut f) = cube();
        let n = v.len() as u32;
        v.extend(cube().0.iter().map(|p| p + shift));
        f.extend(cube().1.iter().map(|t| t.map(|i| i + n)));
        (v, f)
    }

    #[test]
    fn winding_numbers_count_overlapping_parts() {
        let shift = Vec3::new(0.5, 0.3, 0.2);
        for (v, f) in [cube(), two_cubes(shift)] {
            let surface = MeshSurface::new("mesh", &v, &f).unwrap();
            // Off the faces' planes, so that no probe lies on the surface.
            for p in probes().iter().map(|p| p + Vec3::new(0.013, 0.007, 0.003)) {
                let exact = solid_angle_winding(&v, &f, p).round() as i32;
                assert_eq!(surface.winding_number(p), exact, "{p:?}");
            }
        }
        let (v, f) = two_cubes(shift);
        let surface = MeshSurface::new("mesh", &v, &f).unwrap();
        assert_eq!(surface.winding_number(Vec3::new(0.7, 0.6, 0.5)), 2);
        // Inside the first cube only, nearer to a face of the second that lies inside it.
        let p = Vec3::new(0.45, 0.6, 0.5);
        assert_eq!(surface.winding_number(p), 1);
    }

    #[test]
    fn a_fold_facing_inward_does_not_read_as_inside() {
        // The cube with corner 7 pushed through to the far side: the three faces around it
        // now face inward in places, like a skinned armpit folding over itself.
        let (mut v, f) = cube();
        v[7] = Vec3::new(-0.4, 0.45, 0.55);
        let surface = MeshSurface::new("folded", &v, &f).unwrap();
        let mut misread = 0;
        let steps: Vec<f64> = (0..24).map(|k| -0.6 + 0.081 * k as f64).collect();
        for &x in &steps {
            for &y in &steps {
                for &z in &steps {
                    let p = Vec3::new(x, y, z);
                    let exact = solid_angle_winding(&v, &f, p);
                    if (exact - exact.round()).abs() > 1e-6 {
                        continue; // on the surface
                    }
                    let point = to_parry(&p);
                    let (t, (_, (projection, location))) = surface
                        .bvh
                        .find_best(
                            f32::MAX,
                            |node: &BvhNode, _| node.aabb().distance_to_local_point(point, true),
                            |t, _| {
                                let found = surface
                                    .triangle(t)
                                    .project_local_point_and_get_location(point, false);
                                Some(((found.0.point - point).length(), found))
                            },
                        )
                        .unwrap();
                    let facing_in =
                        (point - projection.point).dot(surface.pseudo_normal(t, &location)) <= 0.0;
                    let inside = surface.query(p, f64::INFINITY).unwrap().distance < 0.0;
                    assert_eq!(inside, exact.round() > 0.0, "{p:?}: winding {exact}");
                    if facing_in && exact.round() <= 0.0 {
                        misread += 1;
                    }
                }
            }
        }
        // The pseudo-normal alone would have put these points inside.
        assert!(misread > 0, "the fold never misleads the pseudo-normal");
    }

    #[test]
    fn a_pose_inside_a_sweep_queries_as_if_refit_there() {
        let (v, f) = cube();
        let moved: Vec<Vec3> = v
            .iter()
            .map(|p| Vec3::new(p.x * 1.2 + 0.3, p.y + 0.1 * p.x, p.z))
            .collect();
        let velocity = vec![Vec3::new(0.0, 1.0, 0.0); v.len()];
        let mut swept = MeshSurface::new("cube", &v, &f).unwrap();
        swept.sweep(&v, &moved, &velocity);
        for a in [0.0, 0.3, 1.0] {
            let pose: Vec<Vec3> = v.iter().zip(&moved).map(|(s, e)| s + (e - s) * a).collect();
            swept.place(&pose);
            let mut refit = MeshSurface::new("cube", &v, &f).unwrap();
            refit.update(&pose, &velocity);
            // Shifted off the cube's symmetry planes: no two faces equally close.
            for p in probes().iter().map(|p| p + Vec3::new(0.013, 0.007, 0.003)) {
                assert_eq!(
                    swept.query(p, 0.2).map(|s| (s.distance, s.normal)),
                    refit.query(p, 0.2).map(|s| (s.distance, s.normal)),
                    "{p:?} at a = {a}"
                );
            }
        }
    }

    #[test]
    fn cube_signed_distance_inside_and_out() {
        let (v, f) = cube();
        let m = StaticMesh::new(&v, &f, 0.2).unwrap();
        let s = m.surface_point(Vec3::new(0.5, 0.5, 0.45), 0.01).unwrap();
        assert!((s.distance + 0.45).abs() < 1e-6, "{s:?}");
        assert!((s.normal - Vec3::new(0.0, 0.0, -1.0)).norm() < 1e-6);
        let s = m.surface_point(Vec3::new(0.5, 1.005, 0.5), 0.01).unwrap();
        assert!((s.distance - 0.005).abs() < 1e-6 && (s.normal - Vec3::y()).norm() < 1e-6);
        assert!(m.surface_point(Vec3::new(0.5, 1.5, 0.5), 0.01).is_none());
        let open = &f[..11];
        let error = StaticMesh::new(&v, open, 0.2)
            .err()
            .expect("open mesh rejected");
        assert!(
            matches!(&error, Error::Obstacle { problem, .. } if problem.contains("not closed")),
            "{error}"
        );
    }
}
