//! The garment mesh: 3D positions with triangles, a UV layout with its own triangles (a vertex
//! on a seam has one UV per panel it joins), a panel label per triangle and optional named
//! vertex sets (edge labels of a sewing pattern, such as a collar or a hem).

use std::collections::BTreeMap;

use crate::error::{Error, Result};

/// A garment template.
#[derive(Debug, Clone, PartialEq, Default)]
pub struct Garment {
    /// Name (library name, built-in name or file stem).
    pub name: String,
    /// Vertex positions, metres, aligned to the body in its canonical pose.
    pub positions: Vec<[f64; 3]>,
    /// Triangles over `positions`, counter-clockwise seen from outside the body.
    pub triangles: Vec<[u32; 3]>,
    /// UV coordinates in [0, 1]^2.
    pub uvs: Vec<[f64; 2]>,
    /// Triangles over `uvs`, one per entry of `triangles` (per-corner UVs).
    pub uv_triangles: Vec<[u32; 3]>,
    /// Panel names; `triangle_panels` indexes them.
    pub panels: Vec<String>,
    /// The panel of each triangle.
    pub triangle_panels: Vec<u32>,
    /// Named vertex sets (sorted, unique vertex indices).
    pub vertex_labels: BTreeMap<String, Vec<u32>>,
}

impl Garment {
    /// A garment made of one panel.
    pub fn single_panel(
        name: &str,
        positions: Vec<[f64; 3]>,
        triangles: Vec<[u32; 3]>,
        uvs: Vec<[f64; 2]>,
        uv_triangles: Vec<[u32; 3]>,
    ) -> Self {
        let count = triangles.len();
        Self {
            name: name.to_string(),
            positions,
            triangles,
            uvs,
            uv_triangles,
            panels: vec![name.to_string()],
            triangle_panels: vec![0; count],
            vertex_labels: BTreeMap::new(),
        }
    }

    /// Checks what the engine and the surrogate rely on: indices in range, finite values, a
    /// UV triangle and a panel per triangle, UVs in [0, 1], no triangle repeating a vertex.
    /// [`crate::check`] reports more (manifoldness, orientation, scale) and repairs.
    pub fn validate(&self) -> Result<()> {
        let invalid = |problem: String| {
            Err(Error::BadMesh {
                garment: self.name.clone(),
                problem,
            })
        };
        let n = self.positions.len();
        if self.triangles.is_empty() {
            return invalid("no triangles".into());
        }
        if let Some(i) = self
            .positions
            .iter()
            .position(|p| !p.iter().all(|c| c.is_finite()))
        {
            return invalid(format!("vertex {i} is not finite"));
        }
        if self.uv_triangles.len() != self.triangles.len() {
            return invalid(format!(
                "{} UV triangles for {} triangles",
                self.uv_triangles.len(),
                self.triangles.len()
            ));
        }
        if self.triangle_panels.len() != self.triangles.len() {
            return invalid(format!(
                "{} panel labels for {} triangles",
                self.triangle_panels.len(),
                self.triangles.len()
            ));
        }
        if let Some(t) = self
            .triangle_panels
            .iter()
            .position(|&p| p as usize >= self.panels.len())
        {
            return invalid(format!("triangle {t} names a panel that does not exist"));
        }
        for (t, (tri, uv)) in self.triangles.iter().zip(&self.uv_triangles).enumerate() {
            if tri.iter().any(|&v| v as usize >= n)
                || uv.iter().any(|&v| v as usize >= self.uvs.len())
            {
                return invalid(format!("triangle {t} has an index out of range"));
            }
            if tri[0] == tri[1] || tri[1] == tri[2] || tri[0] == tri[2] {
                return invalid(format!("triangle {t} repeats a vertex"));
            }
        }
        if let Some(i) = self.uvs.iter().position(|uv| {
            !uv.iter()
                .all(|c| c.is_finite() && (-1e-9..=1.0 + 1e-9).contains(c))
        }) {
            return invalid(format!("UV {i} {:?} is outside [0, 1]", self.uvs[i]));
        }
        for (label, vertices) in &self.vertex_labels {
            if vertices.iter().any(|&v| v as usize >= n) {
                return invalid(format!("vertex label '{label}' has an index out of range"));
            }
        }
        Ok(())
    }

    /// Vertex count.
    pub fn num_vertices(&self) -> usize {
        self.positions.len()
    }

    /// Axis-aligned bounding box (min, max) of the positions.
    pub fn bounds(&self) -> ([f64; 3], [f64; 3]) {
        let mut lo = [f64::INFINITY; 3];
        let mut hi = [f64::NEG_INFINITY; 3];
        for p in &self.positions {
            for k in 0..3 {
                lo[k] = lo[k].min(p[k]);
                hi[k] = hi[k].max(p[k]);
            }
        }
        (lo, hi)
    }
}

/// Each vertex's neighbours along the edges of `triangles`, sorted, without repeats (indices at
/// or past `vertex_count` are skipped): the rings that smoothing and untangling average over.
pub fn vertex_neighbours(vertex_count: usize, triangles: &[[u32; 3]]) -> Vec<Vec<u32>> {
    let mut out = vec![Vec::new(); vertex_count];
    for t in triangles {
        for k in 0..3 {
            let v = t[k] as usize;
            if v < vertex_count {
                out[v].extend(
                    [t[(k + 1) % 3], t[(k + 2) % 3]]
                        .into_iter()
                        .filter(|&u| (u as usize) < vertex_count),
                );
            }
        }
    }
    for ring in &mut out {
        ring.sort_unstable();
        ring.dedup();
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn neighbours_are_the_edges_once_each_and_skip_missing_vertices() {
        // Two triangles sharing the edge 1-2, and one reaching past the vertex count.
        let rings = vertex_neighbours(4, &[[0, 1, 2], [2, 1, 3], [3, 2, 9]]);
        assert_eq!(
            rings,
            vec![vec![1, 2], vec![0, 2, 3], vec![0, 1, 3], vec![1, 2]]
        );
    }
}
