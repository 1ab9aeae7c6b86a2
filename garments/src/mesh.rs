//! The garment mesh: 3D positions with triangles, and a UV layout with its own triangles
//! (a vertex on a seam of the UV layout has one UV per side).

use crate::error::{Error, Result};

/// A garment template.
#[derive(Debug, Clone, PartialEq)]
pub struct Garment {
    /// Name (built-in name or file stem).
    pub name: String,
    /// Vertex positions, metres, aligned to the body in its canonical pose.
    pub positions: Vec<[f64; 3]>,
    /// Triangles over `positions`, counter-clockwise seen from outside the body.
    pub triangles: Vec<[u32; 3]>,
    /// UV coordinates in [0, 1]^2.
    pub uvs: Vec<[f64; 2]>,
    /// Triangles over `uvs`, one per entry of `triangles` (per-corner UVs).
    pub uv_triangles: Vec<[u32; 3]>,
}

impl Garment {
    /// Checks indices, finiteness, UV range and degenerate triangles.
    pub fn validate(&self) -> Result<()> {
        let n = self.positions.len();
        if self.triangles.is_empty() {
            return Err(Error::Invalid(format!("'{}' has no triangles", self.name)));
        }
        if let Some(i) = self
            .positions
            .iter()
            .position(|p| !p.iter().all(|c| c.is_finite()))
        {
            return Err(Error::Invalid(format!(
                "'{}': vertex {i} is not finite",
                self.name
            )));
        }
        if self.uv_triangles.len() != self.triangles.len() {
            return Err(Error::Invalid(format!(
                "'{}': {} UV triangles for {} triangles",
                self.name,
                self.uv_triangles.len(),
                self.triangles.len()
            )));
        }
        for (t, (tri, uv)) in self.triangles.iter().zip(&self.uv_triangles).enumerate() {
            if tri.iter().any(|&v| v as usize >= n)
                || uv.iter().any(|&v| v as usize >= self.uvs.len())
            {
                return Err(Error::Invalid(format!(
                    "'{}': triangle {t} has an index out of range",
                    self.name
                )));
            }
            if tri[0] == tri[1] || tri[1] == tri[2] || tri[0] == tri[2] {
                return Err(Error::Invalid(format!(
                    "'{}': triangle {t} repeats a vertex",
                    self.name
                )));
            }
        }
        if let Some(i) = self.uvs.iter().position(|uv| {
            !uv.iter()
                .all(|c| c.is_finite() && (-1e-9..=1.0 + 1e-9).contains(c))
        }) {
            return Err(Error::Invalid(format!(
                "'{}': UV {i} {:?} is outside [0, 1]",
                self.name, self.uvs[i]
            )));
        }
        Ok(())
    }

    /// Vertex count.
    pub fn num_vertices(&self) -> usize {
        self.positions.len()
    }
}
