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
use parry3d::query::{PointQuery, PointQueryWithLocation};
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
                let v = self.faces[t as usize][i as usize];
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
        }
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
        let inside = (point - projection.point).dot(self.pseudo_normal(triangle, &location)) <= 0.0;
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

    /// Whether `p` is within `margin` of the mesh's bounding box.
    pub fn near_bounds(&self, p: Vec3, margin: f64) -> bool {
        let aabb = self.bvh.root_aabb();
        let (lo, hi) = (from_parry(aabb.mins), from_parry(aabb.maxs));
        (0..3).all(|c| p[c] >= lo[c] - margin && p[c] <= hi[c] + margin)
    }
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
        assert!(error.to_string().contains("not closed"));
    }
}
