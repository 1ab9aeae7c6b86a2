//! GarmentCode sewing patterns: parsed and checked ([`Pattern`]), meshed panel by panel with
//! constrained Delaunay refinement (spade), placed in 3D, stitched, and UV-packed
//! ([`Pattern::mesh`] gives a [`SewnMesh`]).
//!
//! Conventions are GarmentCode's: a panel's 2D outline is placed by x3 = R [x, y, 0] + t with
//! R = Rz Ry Rx from Euler degrees; curvature control points are relative to the edge; a
//! stitch joins the end of its first edge to the start of the second (right side to right
//! side) unless it carries `right_wrong`, which joins start to start.

mod curve;
mod meshing;
mod sleeves;
mod spec;
pub(crate) mod uv;

use std::collections::BTreeSet;
use std::path::Path;

pub use curve::{Curve, relative_to_absolute};
pub use meshing::{DEFAULT_EDGE_LENGTH_M, SewnMesh, joined_roots};
pub use sleeves::ARM_ANGLE_DEG;
pub use spec::{EdgeJson, PanelJson, PatternJson, PropertiesJson, SpecFile};

use crate::error::{Error, Result};

/// Stitched edges whose lengths differ by more than this ratio are refused.
pub const MAX_STITCH_LENGTH_RATIO: f64 = 1.5;

/// A checked sewing pattern.
#[derive(Debug, Clone, PartialEq)]
pub struct Pattern {
    /// Name (file stem without `_specification`, or the library name).
    pub name: String,
    /// Panels in panel order.
    pub panels: Vec<Panel>,
    /// Stitches.
    pub stitches: Vec<Stitch>,
    /// Metres per pattern unit (1 / `units_in_meter`).
    pub metres_per_unit: f64,
    /// The specification as read (written back unchanged by [`Pattern::to_json`]).
    pub spec: SpecFile,
}

/// One panel.
#[derive(Debug, Clone, PartialEq)]
pub struct Panel {
    /// Name.
    pub name: String,
    /// Translation, pattern units.
    pub translation: [f64; 3],
    /// Euler angles, degrees.
    pub rotation: [f64; 3],
    /// Outline corners, pattern units.
    pub vertices: Vec<[f64; 2]>,
    /// Edges in loop order.
    pub edges: Vec<Edge>,
}

/// One outline edge.
#[derive(Debug, Clone, PartialEq)]
pub struct Edge {
    /// Start corner.
    pub start: usize,
    /// End corner.
    pub end: usize,
    /// Shape.
    pub curve: Curve,
    /// Label, when given.
    pub label: Option<String>,
}

/// A panel edge named by a stitch.
#[derive(Debug, Clone, Copy, PartialEq, Eq, PartialOrd, Ord)]
pub struct EdgeRef {
    /// Panel index into [`Pattern::panels`].
    pub panel: usize,
    /// Edge index in the panel.
    pub edge: usize,
}

/// Two edges sewn together.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Stitch {
    /// First edge.
    pub a: EdgeRef,
    /// Second edge.
    pub b: EdgeRef,
    /// Start joins start (right side to wrong side) instead of end to start.
    pub right_wrong: bool,
}

impl Panel {
    /// The corners of edge `e`.
    pub fn edge_ends(&self, e: usize) -> ([f64; 2], [f64; 2]) {
        let edge = &self.edges[e];
        (self.vertices[edge.start], self.vertices[edge.end])
    }

    /// Arc length of edge `e`, pattern units.
    pub fn edge_length(&self, e: usize) -> f64 {
        let (s, t) = self.edge_ends(e);
        self.edges[e].curve.length(s, t)
    }

    /// Places a 2D panel point in 3D (pattern units).
    pub fn place(&self, p: [f64; 2]) -> [f64; 3] {
        let r = rotation_matrix(self.rotation);
        let mut out = self.translation;
        for (i, o) in out.iter_mut().enumerate() {
            *o += r[i][0] * p[0] + r[i][1] * p[1];
        }
        out
    }
}

/// R = Rz Ry Rx from Euler degrees (GarmentCode's `euler_xyz_to_R`).
pub fn rotation_matrix(deg: [f64; 3]) -> [[f64; 3]; 3] {
    let [x, y, z] = deg.map(f64::to_radians);
    let (sx, cx, sy, cy, sz, cz) = (x.sin(), x.cos(), y.sin(), y.cos(), z.sin(), z.cos());
    [
        [cz * cy, cz * sy * sx - sz * cx, cz * sy * cx + sz * sx],
        [sz * cy, sz * sy * sx + cz * cx, sz * sy * cx - cz * sx],
        [-sy, cy * sx, cy * cx],
    ]
}

impl Pattern {
    /// Reads and checks a specification file.
    pub fn read(path: &Path) -> Result<Self> {
        let shown = path.display().to_string();
        let text = files::read_to_string(path, files::limits::MESH, "sewing pattern")?;
        let stem = path
            .file_stem()
            .map(|s| s.to_string_lossy().into_owned())
            .unwrap_or_default();
        let name = stem.strip_suffix("_specification").unwrap_or(&stem);
        Self::parse(name, &text).map_err(|e| match e {
            Error::Pattern(message) => Error::Format {
                path: shown,
                message,
            },
            other => other,
        })
    }

    /// Parses and checks specification JSON text.
    pub fn parse(name: &str, text: &str) -> Result<Self> {
        let spec: SpecFile = serde_json::from_str(text)
            .map_err(|e| Error::Pattern(format!("not a GarmentCode specification: {e}")))?;
        Self::from_spec(name, spec)
    }

    /// Checks a specification: units, panels (closed edge loops, valid curvature), stitches
    /// (existing panels and edges, each edge stitched once, similar lengths).
    pub fn from_spec(name: &str, spec: SpecFile) -> Result<Self> {
        let bad = |m: String| Err(Error::Pattern(m));
        let units = spec.properties.units_in_meter;
        if !(units.is_finite() && units > 0.0) {
            return bad(format!(
                "properties.units_in_meter is {units}; it must be positive"
            ));
        }
        if spec.properties.curvature_coords != "relative" {
            return bad(format!(
                "properties.curvature_coords is '{}'; only 'relative' is supported",
                spec.properties.curvature_coords
            ));
        }
        if spec.pattern.panels.is_empty() {
            return bad("pattern.panels is empty".into());
        }
        let order: Vec<String> = match &spec.pattern.panel_order {
            Some(order) => {
                for n in order {
                    if !spec.pattern.panels.contains_key(n) {
                        return bad(format!("panel_order names a missing panel '{n}'"));
                    }
                }
                let listed: BTreeSet<&String> = order.iter().collect();
                let mut all = order.clone();
                all.extend(
                    spec.pattern
                        .panels
                        .keys()
                        .filter(|k| !listed.contains(k))
                        .cloned(),
                );
                all.dedup();
                all
            }
            None => spec.pattern.panels.keys().cloned().collect(),
        };
        let mut panels = Vec::new();
        for panel_name in &order {
            panels.push(parse_panel(panel_name, &spec.pattern.panels[panel_name])?);
        }
        let mut stitches = Vec::new();
        let mut used = BTreeSet::new();
        for (i, raw) in spec.pattern.stitches.iter().enumerate() {
            let stitch = parse_stitch(i, raw, &panels)?;
            for side in [stitch.a, stitch.b] {
                if !used.insert(side) {
                    return bad(format!(
                        "stitch {i}: edge {} of panel '{}' is already stitched",
                        side.edge, panels[side.panel].name
                    ));
                }
            }
            let (la, lb) = (
                panels[stitch.a.panel].edge_length(stitch.a.edge),
                panels[stitch.b.panel].edge_length(stitch.b.edge),
            );
            let ratio = la.max(lb) / la.min(lb).max(1e-12);
            if ratio > MAX_STITCH_LENGTH_RATIO {
                return bad(format!(
                    "stitch {i}: edge {} of '{}' ({la:.2}) and edge {} of '{}' ({lb:.2}) differ \
                     in length by a factor {ratio:.2} (at most {MAX_STITCH_LENGTH_RATIO})",
                    stitch.a.edge,
                    panels[stitch.a.panel].name,
                    stitch.b.edge,
                    panels[stitch.b.panel].name
                ));
            }
            stitches.push(stitch);
        }
        Ok(Self {
            name: name.to_string(),
            panels,
            stitches,
            metres_per_unit: 1.0 / units,
            spec,
        })
    }

    /// The specification as JSON text (what was read, or what the library generated).
    pub fn to_json(&self) -> String {
        serde_json::to_string_pretty(&self.spec).unwrap_or_default()
    }
}

fn parse_panel(name: &str, p: &PanelJson) -> Result<Panel> {
    let bad = |m: String| Err(Error::Pattern(format!("panel '{name}': {m}")));
    if p.vertices.len() < 2 {
        return bad(format!("{} vertices (at least 2)", p.vertices.len()));
    }
    if !p
        .vertices
        .iter()
        .flatten()
        .chain(&p.translation)
        .chain(&p.rotation)
        .all(|c| c.is_finite())
    {
        return bad("a vertex, translation or rotation is not finite".into());
    }
    if p.edges.len() < 2 {
        return bad(format!(
            "{} edges (a closed outline needs 2 or more)",
            p.edges.len()
        ));
    }
    let mut edges = Vec::new();
    for (e, edge) in p.edges.iter().enumerate() {
        let [s, t] = edge.endpoints;
        if s >= p.vertices.len() || t >= p.vertices.len() {
            return bad(format!(
                "edge {e} has endpoints [{s}, {t}] but there are {} vertices",
                p.vertices.len()
            ));
        }
        if s == t {
            return bad(format!("edge {e} starts and ends at vertex {s}"));
        }
        let next = &p.edges[(e + 1) % p.edges.len()];
        if next.endpoints[0] != t {
            return bad(format!(
                "edge {e} ends at vertex {t} but the next edge starts at {}: the outline is not \
                 a closed loop",
                next.endpoints[0]
            ));
        }
        let curve = match &edge.curvature {
            None => Curve::Line,
            Some(c) => parse_curvature(c)
                .map_err(|m| Error::Pattern(format!("panel '{name}': edge {e} curvature: {m}")))?,
        };
        edges.push(Edge {
            start: s,
            end: t,
            curve,
            label: edge.label.clone(),
        });
    }
    Ok(Panel {
        name: name.to_string(),
        translation: p.translation,
        rotation: p.rotation,
        vertices: p.vertices.clone(),
        edges,
    })
}

fn point(v: &serde_json::Value) -> Option<[f64; 2]> {
    let a = v.as_array()?;
    if a.len() != 2 {
        return None;
    }
    let p = [a[0].as_f64()?, a[1].as_f64()?];
    p.iter().all(|c| c.is_finite()).then_some(p)
}

fn flag(v: &serde_json::Value) -> Option<bool> {
    v.as_bool().or_else(|| v.as_f64().map(|x| x != 0.0))
}

fn parse_curvature(c: &serde_json::Value) -> std::result::Result<Curve, String> {
    // Old patterns give a bare [t, h] for a quadratic.
    if let Some(p) = point(c) {
        return Ok(Curve::Quadratic(p));
    }
    let kind = c
        .get("type")
        .and_then(|t| t.as_str())
        .ok_or("needs a 'type' (quadratic, cubic or circle)")?;
    let params = c
        .get("params")
        .and_then(|p| p.as_array())
        .ok_or("needs a 'params' list")?;
    match kind {
        "quadratic" => match params.as_slice() {
            [p] => point(p)
                .map(Curve::Quadratic)
                .ok_or("quadratic params: [[t, h]]".into()),
            _ => Err("quadratic params: [[t, h]]".into()),
        },
        "cubic" => match params.as_slice() {
            [a, b] => match (point(a), point(b)) {
                (Some(a), Some(b)) => Ok(Curve::Cubic([a, b])),
                _ => Err("cubic params: [[t1, h1], [t2, h2]]".into()),
            },
            _ => Err("cubic params: [[t1, h1], [t2, h2]]".into()),
        },
        "circle" => match params.as_slice() {
            [r, large, right] => match (r.as_f64(), flag(large), flag(right)) {
                (Some(radius), Some(large_arc), Some(right))
                    if radius.is_finite() && radius > 0.0 =>
                {
                    Ok(Curve::Circle {
                        radius,
                        large_arc,
                        right,
                    })
                }
                _ => Err("circle params: [radius > 0, large_arc, right]".into()),
            },
            _ => Err("circle params: [radius, large_arc, right]".into()),
        },
        other => Err(format!(
            "unknown type '{other}' (quadratic, cubic or circle)"
        )),
    }
}

fn parse_stitch(i: usize, raw: &[serde_json::Value], panels: &[Panel]) -> Result<Stitch> {
    let bad = |m: String| Err(Error::Pattern(format!("stitch {i}: {m}")));
    let right_wrong = match raw.get(2) {
        None => false,
        Some(v) if v.as_str() == Some("right_wrong") => true,
        Some(v) => return bad(format!("third element {v} is not \"right_wrong\"")),
    };
    if raw.len() < 2 || raw.len() > 3 {
        return bad(format!(
            "{} elements (2, or 3 with \"right_wrong\")",
            raw.len()
        ));
    }
    let mut sides = Vec::new();
    for side in &raw[..2] {
        let panel_name = side
            .get("panel")
            .and_then(|p| p.as_str())
            .ok_or_else(|| Error::Pattern(format!("stitch {i}: a side has no 'panel' name")))?;
        let edge = side
            .get("edge")
            .and_then(|e| e.as_u64())
            .ok_or_else(|| Error::Pattern(format!("stitch {i}: a side has no 'edge' index")))?
            as usize;
        let Some(panel) = panels.iter().position(|p| p.name == panel_name) else {
            return bad(format!("panel '{panel_name}' does not exist"));
        };
        if edge >= panels[panel].edges.len() {
            return bad(format!(
                "panel '{panel_name}' has {} edges, no edge {edge}",
                panels[panel].edges.len()
            ));
        }
        sides.push(EdgeRef { panel, edge });
    }
    if sides[0] == sides[1] {
        return bad("an edge is stitched to itself".into());
    }
    Ok(Stitch {
        a: sides[0],
        b: sides[1],
        right_wrong,
    })
}
