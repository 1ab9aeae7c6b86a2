//! Triangle-mesh obstacles on parry3d: BVH closest-point queries with the inside test from
//! pseudo-normals (a closed, consistently oriented mesh), refit in place when the mesh moves.
//! parry3d works in f32; positions are converted at the boundary (1e-7 m is far below any
//! contact tolerance).

use parry3d::math::Vector;
use parry3d::query::PointQueryWithLocation;
use parry3d::shape::{TriMesh, TriMeshFlags};

use super::{Obstacle, SurfacePoint};
use crate::cloth::{Vec3, to_parry};
use crate::error::{Error, Result};

fn from_parry(p: Vector) -> Vec3 {
    Vec3::new(p.x as f64, p.y as f64, p.z as f64)
}

/// A closed triangle mesh with per-vertex velocities, queried for signed distances (the
/// engine's body and props, and the surrogate's intersection guidance).
pub struct MeshSurface {
    mesh: TriMesh,
    faces: Vec<[u32; 3]>,
    velocities: Vec<Vec3>,
    scratch: Vec<Vector>,
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
        let open = motions::boundary_edges(faces);
        if open > 0 {
            return Err(fail(format!(
                "the mesh is not closed ({open} boundary edges); the inside test needs a closed, consistently oriented surface"
            )));
        }
        let mesh = TriMesh::with_flags(
            vertices.iter().map(to_parry).collect(),
            faces.to_vec(),
            TriMeshFlags::ORIENTED | TriMeshFlags::DEFORMABLE,
        )
        .map_err(|e| fail(format!("{e:?}")))?;
        Ok(Self {
            mesh,
            faces: faces.to_vec(),
            velocities: vec![Vec3::zeros(); vertices.len()],
            scratch: Vec::with_capacity(vertices.len()),
        })
    }

    /// Vertices of the mesh.
    pub fn num_vertices(&self) -> usize {
        self.velocities.len()
    }

    /// Moves the vertices (refits the BVH and the pseudo-normals) and sets their velocities.
    pub fn update(&mut self, vertices: &[Vec3], velocities: &[Vec3]) {
        self.scratch.clear();
        self.scratch.extend(vertices.iter().map(to_parry));
        self.mesh.set_vertices(&self.scratch);
        self.velocities.copy_from_slice(velocities);
    }

    /// The closest surface point if within `max_distance`, else `None` (whatever the side).
    pub fn query(&self, p: Vec3, max_distance: f64) -> Option<SurfacePoint> {
        let point = to_parry(&p);
        let (projection, (triangle, location)) = if max_distance.is_finite() {
            self.mesh
                .project_local_point_and_get_location_with_max_dist(
                    point,
                    false,
                    max_distance as f32,
                )?
        } else {
            self.mesh.project_local_point_and_get_location(point, false)
        };
        let closest = from_parry(projection.point);
        let offset = p - closest;
        let length = offset.norm();
        let sign = if projection.is_inside { -1.0 } else { 1.0 };
        let face = self.faces[triangle as usize];
        let normal = if length > 1e-7 {
            offset * (sign / length)
        } else {
            let t = self.mesh.triangle(triangle);
            from_parry(t.scaled_normal()).normalize()
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
        let aabb = self.mesh.local_aabb();
        let (lo, hi) = (from_parry(aabb.mins), from_parry(aabb.maxs));
        (0..3).all(|c| p[c] >= lo[c] - margin && p[c] <= hi[c] + margin)
    }
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
