//! The cloth: its mesh (rest shape and triangles, validated once) and its state (positions
//! and velocities), kept apart from the solver's workspace.

use std::collections::BTreeMap;

use nalgebra::Vector3;

use crate::error::{MeshError, Result};

/// 3-vector of f64, the engine's one vector type.
pub type Vec3 = Vector3<f64>;

/// A triangle mesh in its rest shape. The rest shape gives the edges' rest lengths and the
/// bending rest state; it is usually the draped template.
#[derive(Debug, Clone)]
pub struct ClothMesh {
    rest: Vec<Vec3>,
    triangles: Vec<[u32; 3]>,
    edges: Vec<[u32; 2]>,
    areas: Vec<f64>,
}

impl ClothMesh {
    /// Builds and validates a mesh: at least one triangle, indices in range, finite positions,
    /// no degenerate triangle (area below 1e-12 m^2) and every vertex used.
    pub fn new(rest: Vec<Vec3>, triangles: Vec<[u32; 3]>) -> Result<Self> {
        if triangles.is_empty() {
            return Err(MeshError::NoTriangles.into());
        }
        let n = rest.len();
        if let Some(i) = rest.iter().position(|p| !p.iter().all(|c| c.is_finite())) {
            return Err(MeshError::NonFiniteVertex { vertex: i }.into());
        }
        let mut used = vec![false; n];
        let mut edge_set = BTreeMap::new();
        let mut areas = Vec::with_capacity(triangles.len());
        for (t, tri) in triangles.iter().enumerate() {
            if let Some(&vertex) = tri.iter().find(|&&v| v as usize >= n) {
                return Err(MeshError::MissingVertex {
                    triangle: t,
                    vertex,
                    vertices: n,
                }
                .into());
            }
            let [a, b, c] = tri.map(|v| rest[v as usize]);
            let area = 0.5 * (b - a).cross(&(c - a)).norm();
            if area < 1e-12 {
                return Err(MeshError::Degenerate {
                    triangle: t,
                    corners: *tri,
                }
                .into());
            }
            areas.push(area);
            for k in 0..3 {
                used[tri[k] as usize] = true;
                let (i, j) = (tri[k], tri[(k + 1) % 3]);
                edge_set.insert([i.min(j), i.max(j)], ());
            }
        }
        if let Some(i) = used.iter().position(|u| !u) {
            return Err(MeshError::UnusedVertex { vertex: i }.into());
        }
        Ok(Self {
            rest,
            triangles,
            edges: edge_set.into_keys().collect(),
            areas,
        })
    }

    /// Vertex count.
    pub fn num_vertices(&self) -> usize {
        self.rest.len()
    }

    /// Rest positions, metres.
    pub fn rest(&self) -> &[Vec3] {
        &self.rest
    }

    /// Triangles (vertex indices).
    pub fn triangles(&self) -> &[[u32; 3]] {
        &self.triangles
    }

    /// Unique edges, each as (smaller index, larger index), sorted.
    pub fn edges(&self) -> &[[u32; 2]] {
        &self.edges
    }

    /// Rest area of each triangle, m^2.
    pub fn triangle_areas(&self) -> &[f64] {
        &self.areas
    }

    /// Lumped vertex masses, kg: density times a third of the adjacent triangles' rest area.
    pub fn lumped_masses(&self, density: f64) -> Vec<f64> {
        let mut mass = vec![0.0; self.rest.len()];
        for (tri, area) in self.triangles.iter().zip(&self.areas) {
            for &v in tri {
                mass[v as usize] += density * area / 3.0;
            }
        }
        mass
    }

    /// Total rest area, m^2.
    pub fn area(&self) -> f64 {
        self.areas.iter().sum()
    }

    /// Vertices on the boundary (on an edge used by one triangle only).
    pub fn boundary_vertices(&self) -> Vec<bool> {
        let mut count: BTreeMap<[u32; 2], u32> = BTreeMap::new();
        for tri in &self.triangles {
            for k in 0..3 {
                let (i, j) = (tri[k], tri[(k + 1) % 3]);
                *count.entry([i.min(j), i.max(j)]).or_default() += 1;
            }
        }
        let mut boundary = vec![false; self.rest.len()];
        for (edge, c) in count {
            if c == 1 {
                boundary[edge[0] as usize] = true;
                boundary[edge[1] as usize] = true;
            }
        }
        boundary
    }

    /// A near-equilateral sheet in the x-y plane (z = 0): `columns` vertices per row spaced
    /// `spacing` apart along x, `rows` rows spaced spacing sqrt(3)/2 apart going down (-y) from
    /// y = 0, odd rows shifted by half a spacing. Vertex index row * columns + column.
    pub fn equilateral(columns: usize, rows: usize, spacing: f64) -> Result<Self> {
        if columns < 2 || rows < 2 {
            return Err(MeshError::GridTooSmall { columns, rows }.into());
        }
        let dy = spacing * 3f64.sqrt() / 2.0;
        let mut rest = Vec::with_capacity(columns * rows);
        for r in 0..rows {
            let shift = if r % 2 == 1 { 0.5 * spacing } else { 0.0 };
            for c in 0..columns {
                rest.push(Vec3::new(c as f64 * spacing + shift, -(r as f64) * dy, 0.0));
            }
        }
        let id = |r: usize, c: usize| (r * columns + c) as u32;
        let mut triangles = Vec::new();
        for r in 0..rows - 1 {
            for c in 0..columns - 1 {
                if r % 2 == 0 {
                    triangles.push([id(r, c), id(r + 1, c), id(r, c + 1)]);
                    triangles.push([id(r, c + 1), id(r + 1, c), id(r + 1, c + 1)]);
                } else {
                    triangles.push([id(r, c), id(r + 1, c + 1), id(r, c + 1)]);
                    triangles.push([id(r, c), id(r + 1, c), id(r + 1, c + 1)]);
                }
            }
        }
        Self::new(rest, triangles)
    }

    /// A regular n x n grid of `size` x `size` metres in the x-z plane at height `y`, vertex
    /// index i * n + j for x index i and z index j, each quad split along the same diagonal
    /// (the peer simulators' drape-scene layout).
    pub fn grid(n: usize, size: f64, y: f64) -> Result<Self> {
        if n < 2 {
            return Err(MeshError::GridTooSmall {
                columns: n,
                rows: n,
            }
            .into());
        }
        let step = size / (n - 1) as f64;
        let mut rest = Vec::with_capacity(n * n);
        for i in 0..n {
            for j in 0..n {
                rest.push(Vec3::new(
                    -0.5 * size + i as f64 * step,
                    y,
                    -0.5 * size + j as f64 * step,
                ));
            }
        }
        let mut triangles = Vec::with_capacity(2 * (n - 1) * (n - 1));
        let id = |i: usize, j: usize| (i * n + j) as u32;
        for i in 0..n - 1 {
            for j in 0..n - 1 {
                let (a, b, c, d) = (id(i, j), id(i + 1, j), id(i + 1, j + 1), id(i, j + 1));
                triangles.push([a, b, c]);
                triangles.push([a, c, d]);
            }
        }
        Self::new(rest, triangles)
    }
}

/// Positions and velocities of every cloth vertex.
#[derive(Debug, Clone, PartialEq)]
pub struct ClothState {
    /// Positions, metres.
    pub positions: Vec<Vec3>,
    /// Velocities, m/s.
    pub velocities: Vec<Vec3>,
}

impl ClothState {
    /// At rest at the given positions.
    pub fn at_rest(positions: Vec<Vec3>) -> Self {
        let velocities = vec![Vec3::zeros(); positions.len()];
        Self {
            positions,
            velocities,
        }
    }

    /// Whether every value is finite.
    pub fn is_finite(&self) -> bool {
        self.positions
            .iter()
            .chain(&self.velocities)
            .all(|p| p.iter().all(|c| c.is_finite()))
    }
}

/// The point in parry3d's f32 vector type (1e-7 m is far below any contact tolerance).
pub(crate) fn to_parry(p: &Vec3) -> parry3d::math::Vector {
    parry3d::math::Vector::new(p.x as f32, p.y as f32, p.z as f32)
}

/// Closest point on triangle (a, b, c) to p, with barycentric coordinates (Ericson, RTCD 5.1.5).
pub(crate) fn closest_on_triangle(p: Vec3, a: Vec3, b: Vec3, c: Vec3) -> (Vec3, [f64; 3]) {
    let (ab, ac, ap) = (b - a, c - a, p - a);
    let (d1, d2) = (ab.dot(&ap), ac.dot(&ap));
    if d1 <= 0.0 && d2 <= 0.0 {
        return (a, [1.0, 0.0, 0.0]);
    }
    let bp = p - b;
    let (d3, d4) = (ab.dot(&bp), ac.dot(&bp));
    if d3 >= 0.0 && d4 <= d3 {
        return (b, [0.0, 1.0, 0.0]);
    }
    let vc = d1 * d4 - d3 * d2;
    if vc <= 0.0 && d1 >= 0.0 && d3 <= 0.0 {
        let v = d1 / (d1 - d3);
        return (a + ab * v, [1.0 - v, v, 0.0]);
    }
    let cp = p - c;
    let (d5, d6) = (ab.dot(&cp), ac.dot(&cp));
    if d6 >= 0.0 && d5 <= d6 {
        return (c, [0.0, 0.0, 1.0]);
    }
    let vb = d5 * d2 - d1 * d6;
    if vb <= 0.0 && d2 >= 0.0 && d6 <= 0.0 {
        let w = d2 / (d2 - d6);
        return (a + ac * w, [1.0 - w, 0.0, w]);
    }
    let va = d3 * d6 - d5 * d4;
    if va <= 0.0 && (d4 - d3) >= 0.0 && (d5 - d6) >= 0.0 {
        let w = (d4 - d3) / ((d4 - d3) + (d5 - d6));
        return (b + (c - b) * w, [0.0, 1.0 - w, w]);
    }
    let denom = 1.0 / (va + vb + vc);
    let (v, w) = (vb * denom, vc * denom);
    (a + ab * v + ac * w, [1.0 - v - w, v, w])
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn grid_topology_and_mass() {
        let mesh = ClothMesh::grid(3, 1.0, 0.0).unwrap();
        assert_eq!(mesh.num_vertices(), 9);
        assert_eq!(mesh.triangles().len(), 8);
        // 2 * 3 * 2 axis edges + 4 diagonals
        assert_eq!(mesh.edges().len(), 16);
        let total: f64 = mesh.lumped_masses(0.5).iter().sum();
        assert!((total - 0.5).abs() < 1e-12, "total mass {total}");
        let boundary = mesh.boundary_vertices();
        assert_eq!(boundary.iter().filter(|b| **b).count(), 8);
        assert!(!boundary[4]);
    }

    #[test]
    fn bad_meshes_are_rejected_with_a_reason() {
        let p = vec![Vec3::zeros(), Vec3::x(), Vec3::y()];
        assert!(
            ClothMesh::new(p.clone(), vec![[0, 1, 3]])
                .unwrap_err()
                .to_string()
                .contains("vertex")
        );
        assert!(
            ClothMesh::new(p.clone(), vec![[0, 1, 1]])
                .unwrap_err()
                .to_string()
                .contains("degenerate")
        );
        assert!(ClothMesh::new(p.clone(), vec![]).is_err());
        let mut q = p.clone();
        q[1].x = f64::NAN;
        assert!(
            ClothMesh::new(q, vec![[0, 1, 2]])
                .unwrap_err()
                .to_string()
                .contains("finite")
        );
        let mut r = p;
        r.push(Vec3::z());
        assert!(
            ClothMesh::new(r, vec![[0, 1, 2]])
                .unwrap_err()
                .to_string()
                .contains("used by no")
        );
    }
}
