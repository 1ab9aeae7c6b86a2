//! Mesh validation with documented repairs, for files users bring.
//!
//! [`check`] lists every problem it finds; [`repair`] applies the repairs below and refuses
//! what cannot be repaired:
//!
//! | problem | repair |
//! |---|---|
//! | more than 50,000 vertices, or a vertex in more than 64 triangles (a fan) | none: refused |
//! | non-finite positions or UVs, indices out of range | none: refused |
//! | missing UVs | none: refused (templates need UVs for the surrogate) |
//! | UVs outside [0, 1] | all UVs moved and scaled uniformly into [0, 1] |
//! | degenerate triangles (a repeated vertex, or area < 1e-12 m^2) | removed |
//! | duplicate triangles (same three vertices) | the copies removed |
//! | unreferenced vertices | removed, the rest renumbered |
//! | non-manifold edges (three or more triangles) | none: refused |
//! | inconsistent orientation between neighbours | flipped to agree with the first triangle of each connected piece; refused when no consistent orientation exists |
//! | orientation pointing into the body (normals towards the piece's vertical axis) | the piece flipped |
//! | implausible scale (largest extent over 3 m or under 5 cm, e.g. a file in cm) | refused (`garments check FILE --scale 0.01` tells whether a scale fixes it) |

mod elements;
mod orientation;
mod topology;

use crate::error::{Error, Result};
use crate::mesh::Garment;

use elements::normalize_uvs;
pub(crate) use orientation::outward_score;
use orientation::{inward_pieces, orient};
#[cfg(test)]
pub(crate) use topology::doubled_normal;
pub(crate) use topology::remove_unreferenced;
use topology::{degenerate_triangles, duplicate_triangles, edge_triangles, keep_triangles};

/// Largest plausible garment extent, m.
pub const MAX_EXTENT_M: f64 = 3.0;
/// Smallest plausible garment extent, m.
pub const MIN_EXTENT_M: f64 = 0.05;
/// The most vertices a template may have: six times the largest library design; past it the
/// engine's self-contact and intersection counts take minutes a frame.
pub const MAX_TEMPLATE_VERTICES: usize = 50_000;
/// The most triangles one vertex may be in (cloth meshes have 4 to 12): a vertex in more is
/// the apex of a fan from a triangulated polygon, whose slivers no solver handles.
pub const MAX_VERTEX_TRIANGLES: usize = 64;

/// One kind of problem found, with how many and an example.
#[derive(Debug, Clone, PartialEq)]
pub struct Finding {
    /// What is wrong (stable wording, e.g. "non-manifold edges").
    pub problem: &'static str,
    /// How many elements have it.
    pub count: usize,
    /// The first one, in words.
    pub example: String,
    /// What [`repair`] does about it; `None` when the mesh is refused.
    pub repair: Option<&'static str>,
}

/// What [`check`] found.
#[derive(Debug, Clone, PartialEq)]
pub struct CheckReport {
    /// Vertex count.
    pub vertices: usize,
    /// Triangle count.
    pub triangles: usize,
    /// Panel count.
    pub panels: usize,
    /// Bounding-box size, m.
    pub extent_m: [f64; 3],
    /// Problems, in the order of the table in the module docs.
    pub findings: Vec<Finding>,
}

impl CheckReport {
    /// True when nothing needs refusing (repairs may still apply).
    pub fn repairable(&self) -> bool {
        self.findings.iter().all(|f| f.repair.is_some())
    }

    /// One line per finding.
    pub fn lines(&self) -> Vec<String> {
        self.findings
            .iter()
            .map(|f| {
                format!(
                    "{}: {} (e.g. {}) -> {}",
                    f.problem,
                    f.count,
                    f.example,
                    f.repair.unwrap_or("cannot be repaired")
                )
            })
            .collect()
    }
}

/// What `garments check` reports of an OBJ file: the counts and one line per finding.
#[derive(Debug, Clone, serde::Serialize)]
pub struct FileCheck {
    /// The file as given.
    pub file: String,
    /// Whether the mesh can be used (every finding repairable).
    pub usable: bool,
    /// Vertex count.
    pub vertices: usize,
    /// Triangle count.
    pub triangles: usize,
    /// Panel count.
    pub panels: usize,
    /// Bounding-box size, m.
    pub extent_m: [f64; 3],
    /// One line per finding ([`CheckReport::lines`]).
    pub findings: Vec<String>,
}

/// Checks the OBJ mesh at `path`, its positions scaled by `scale` first (0.01 for cm),
/// naming vertices by their numbers in the file.
pub fn check_obj_file(path: &std::path::Path, scale: f64) -> crate::Result<FileCheck> {
    let (mut raw, numbers) = crate::read_obj_numbered(path)?;
    for p in &mut raw.positions {
        *p = p.map(|c| c * scale);
    }
    let report = check_numbered(&raw, Some(&numbers));
    Ok(FileCheck {
        file: path.display().to_string(),
        usable: report.repairable(),
        vertices: report.vertices,
        triangles: report.triangles,
        panels: report.panels,
        extent_m: report.extent_m,
        findings: report.lines(),
    })
}

/// Lists every problem of the mesh (see the module docs).
pub fn check(g: &Garment) -> CheckReport {
    check_numbered(g, None)
}

/// [`check`], naming vertices by `numbers` (the 1-based `v` number of each vertex in the OBJ
/// file it was read from, see [`crate::read_obj_numbered`]) rather than by their index here.
pub fn check_numbered(g: &Garment, numbers: Option<&[u32]>) -> CheckReport {
    let vertex = |i: usize| match numbers.and_then(|n| n.get(i)) {
        Some(k) => format!("OBJ vertex {k}"),
        None => format!("vertex {i}"),
    };
    let (lo, hi) = g.bounds();
    let extent = if g.positions.is_empty() {
        [0.0; 3]
    } else {
        [hi[0] - lo[0], hi[1] - lo[1], hi[2] - lo[2]]
    };
    let mut findings = Vec::new();
    elements::element_findings(g, &vertex, &mut findings);
    // Topology checks need valid indices and positions.
    if findings.iter().all(|f| f.repair.is_some()) {
        let topology = topology::topology_findings(g, &vertex, &mut findings);
        if findings.iter().all(|f| f.repair.is_some()) {
            orientation::orientation_findings(g, &topology, &mut findings);
        }
        elements::scale_findings(g, &topology.used, &mut findings);
    }
    CheckReport {
        vertices: g.positions.len(),
        triangles: g.triangles.len(),
        panels: g.panels.len(),
        extent_m: extent,
        findings,
    }
}

/// Scales the positions by `scale`, then applies the documented repairs; refuses what cannot
/// be repaired with an error listing every such problem. Returns the repaired garment and one
/// line per repair made.
pub fn repair(g: &Garment, scale: f64) -> Result<(Garment, Vec<String>)> {
    repair_numbered(g, scale, None)
}

/// [`repair`], naming vertices in a refusal by their OBJ `v` numbers (see [`check_numbered`]).
pub fn repair_numbered(
    g: &Garment,
    scale: f64,
    numbers: Option<&[u32]>,
) -> Result<(Garment, Vec<String>)> {
    if !(scale.is_finite() && scale > 0.0) {
        return Err(Error::BadParameter {
            parameter: "scale",
            problem: format!("{scale} is not positive"),
        });
    }
    let mut g = g.clone();
    for p in &mut g.positions {
        for c in p.iter_mut() {
            *c *= scale;
        }
    }
    let report = check_numbered(&g, numbers);
    if !report.repairable() {
        let findings: Vec<String> = report
            .findings
            .iter()
            .filter(|f| f.repair.is_none())
            .map(|f| format!("{} ({}, e.g. {})", f.problem, f.count, f.example))
            .collect();
        return Err(Error::Unrepairable {
            garment: g.name,
            findings,
        });
    }
    let done = report.lines();
    if report
        .findings
        .iter()
        .any(|f| f.problem == "UVs outside [0, 1]")
    {
        normalize_uvs(&mut g.uvs);
    }
    let degenerate = degenerate_triangles(&g);
    let duplicates = duplicate_triangles(&g, &degenerate);
    let kept: Vec<usize> = (0..g.triangles.len())
        .filter(|t| !degenerate.contains(t) && !duplicates.contains(t))
        .collect();
    let edges = edge_triangles(&g.triangles, &kept);
    let flips = orient(&g.triangles, &kept, &edges).unwrap_or_default();
    for &t in &flips {
        g.triangles[t].swap(1, 2);
        g.uv_triangles[t].swap(1, 2);
    }
    for piece in inward_pieces(&g.positions, &g.triangles, &kept, &edges) {
        for t in piece {
            g.triangles[t].swap(1, 2);
            g.uv_triangles[t].swap(1, 2);
        }
    }
    keep_triangles(&mut g, &kept);
    remove_unreferenced(&mut g);
    g.validate()?;
    Ok((g, done))
}

fn add(
    findings: &mut Vec<Finding>,
    problem: &'static str,
    items: Vec<String>,
    repair: Option<&'static str>,
) {
    if let Some(first) = items.first() {
        findings.push(Finding {
            problem,
            count: items.len(),
            example: first.clone(),
            repair,
        });
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn tube() -> Garment {
        crate::builtin::tube_for_tests()
    }

    fn problems(g: &Garment) -> Vec<&'static str> {
        check(g).findings.iter().map(|f| f.problem).collect()
    }

    /// A tube in cm is refused until scaled to metres; vertices are named by their numbers
    /// in the file.
    #[test]
    fn an_obj_file_is_checked_at_its_scale() {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("tube.obj");
        let mut cm = tube();
        for p in &mut cm.positions {
            *p = p.map(|c| c * 100.0);
        }
        files::write_with(&path, |w| crate::write_obj(w, &cm, None)).unwrap();
        let raw = check_obj_file(&path, 1.0).unwrap();
        assert!(!raw.usable, "{raw:?}");
        assert!(raw.findings.iter().any(|f| f.contains("extent")), "{raw:?}");
        let metres = check_obj_file(&path, 0.01).unwrap();
        assert!(metres.usable && metres.findings.is_empty(), "{metres:?}");
        assert_eq!(metres.vertices, tube().positions.len());
        assert!(metres.file.ends_with("tube.obj"));
    }

    #[test]
    fn a_clean_tube_has_no_findings() {
        assert!(check(&tube()).findings.is_empty(), "{:?}", check(&tube()));
    }

    #[test]
    fn repairs_degenerate_duplicate_unreferenced_flipped_and_inward() {
        let mut g = tube();
        let n = g.triangles.len();
        g.triangles.push(g.triangles[0]);
        g.uv_triangles.push(g.uv_triangles[0]);
        g.triangle_panels.push(0);
        g.triangles.push([0, 0, 1]);
        g.uv_triangles.push([0, 0, 1]);
        g.triangle_panels.push(0);
        g.positions.push([5.0, 5.0, 5.0]);
        g.triangles[3].swap(1, 2);
        assert_eq!(
            problems(&g),
            [
                "degenerate triangles",
                "duplicate triangles",
                "unreferenced vertices",
                "inconsistent orientation"
            ]
        );
        let (fixed, done) = repair(&g, 1.0).unwrap();
        assert_eq!(done.len(), 4);
        assert_eq!(fixed.triangles.len(), n);
        assert!(check(&fixed).findings.is_empty(), "{:?}", check(&fixed));

        let mut inward = tube();
        for t in &mut inward.triangles {
            t.swap(1, 2);
        }
        assert_eq!(problems(&inward), ["orientation pointing into the body"]);
        let (fixed, _) = repair(&inward, 1.0).unwrap();
        assert_eq!(fixed.triangles, tube().triangles);
    }

    #[test]
    fn refuses_what_cannot_be_repaired() {
        let mut cm = tube();
        for p in &mut cm.positions {
            *p = p.map(|c| c * 100.0);
        }
        assert_eq!(problems(&cm), ["implausible scale"]);
        assert!(
            repair(&cm, 1.0)
                .unwrap_err()
                .to_string()
                .contains("--scale")
        );
        assert!(repair(&cm, 0.01).is_ok());

        let mut fin = tube();
        fin.triangles.push([0, 1, 17]);
        fin.uv_triangles.push([0, 1, 17]);
        fin.triangle_panels.push(0);
        fin.triangles.push([0, 1, 18]);
        fin.uv_triangles.push([0, 1, 18]);
        fin.triangle_panels.push(0);
        assert!(problems(&fin).contains(&"non-manifold edges"));
        assert!(repair(&fin, 1.0).is_err());

        let mut nan = tube();
        nan.positions[4][1] = f64::NAN;
        assert_eq!(problems(&nan), ["non-finite positions"]);
        let mut no_uv = tube();
        no_uv.uv_triangles.clear();
        assert_eq!(problems(&no_uv), ["missing UVs"]);
        let mut far_uv = tube();
        far_uv.uvs[0] = [1.5, 0.0];
        assert_eq!(problems(&far_uv), ["UVs outside [0, 1]"]);
        let (fixed, _) = repair(&far_uv, 1.0).unwrap();
        fixed.validate().unwrap();
        let mut bad_index = tube();
        bad_index.triangles[0][0] = 10_000;
        assert_eq!(problems(&bad_index), ["indices out of range"]);
    }
}
