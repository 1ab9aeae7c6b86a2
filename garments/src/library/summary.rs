//! A design as `garments list` shows it: its size at the default resolution.

use serde::Serialize;

use super::Design;
use crate::Result;
use crate::pattern::DEFAULT_EDGE_LENGTH_M;

/// One design's line: name, split, mesh size once sewn, what it is.
#[derive(Debug, Clone, Serialize)]
pub struct DesignSummary {
    /// Name.
    pub name: &'static str,
    /// `train` or `test`.
    pub split: &'static str,
    /// Template vertices at the default edge length.
    pub vertices: usize,
    /// Template triangles.
    pub triangles: usize,
    /// Panels.
    pub panels: usize,
    /// What it is.
    pub description: &'static str,
}

/// The line `garments list` prints: name, split, vertices, panels, what it is.
impl std::fmt::Display for DesignSummary {
    fn fmt(&self, f: &mut std::fmt::Formatter) -> std::fmt::Result {
        let (name, split, vertices, panels) = (self.name, self.split, self.vertices, self.panels);
        write!(
            f,
            "{name:<24} {split:<6} {vertices:>8} {panels:>6}  {}",
            self.description
        )
    }
}

impl Design {
    /// Meshes the design at the default edge length and counts its template.
    pub fn summary(&self) -> Result<DesignSummary> {
        let mesh = self.pattern()?.mesh(DEFAULT_EDGE_LENGTH_M)?;
        let merged = mesh.merged(&mesh.garment.positions)?;
        Ok(DesignSummary {
            name: self.name,
            split: self.split,
            vertices: merged.positions.len(),
            triangles: merged.triangles.len(),
            panels: merged.panels.len(),
            description: self.description,
        })
    }
}

#[cfg(test)]
mod tests {
    use crate::library::DESIGNS;

    #[test]
    fn a_summary_counts_the_sewn_template() {
        let s = DESIGNS[0].summary().unwrap();
        assert_eq!(s.name, DESIGNS[0].name);
        assert!(
            s.vertices > 100 && s.triangles > s.vertices && s.panels >= 2,
            "{s:?}"
        );
    }
}
