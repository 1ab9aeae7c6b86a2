//! The GarmentCode specification JSON, as serde types that read and write it unchanged.

use std::collections::BTreeMap;

use serde::{Deserialize, Serialize};

/// A whole `*_specification.json` file.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct SpecFile {
    /// Panels, stitches and panel order.
    pub pattern: PatternJson,
    /// Design parameters (free-form; kept as they are).
    #[serde(default)]
    pub parameters: serde_json::Value,
    /// Order of the design parameters (free-form).
    #[serde(default)]
    pub parameter_order: serde_json::Value,
    /// Units and conventions.
    pub properties: PropertiesJson,
}

/// `properties`.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct PropertiesJson {
    /// Must be "relative" (control points in the edge's frame).
    #[serde(default = "relative")]
    pub curvature_coords: String,
    /// GarmentCode's one-time normalization flag (must be false: coordinates are final).
    #[serde(default)]
    pub normalize_panel_translation: bool,
    /// GarmentCode's edge-loop normalization flag (kept).
    #[serde(default = "yes")]
    pub normalized_edge_loops: bool,
    /// Pattern units per metre (100 = cm).
    pub units_in_meter: f64,
}

fn relative() -> String {
    "relative".into()
}

fn yes() -> bool {
    true
}

/// `pattern`.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct PatternJson {
    /// Panels by name.
    pub panels: BTreeMap<String, PanelJson>,
    /// Stitches: `[{panel, edge}, {panel, edge}]` with an optional third element
    /// `"right_wrong"`.
    #[serde(default)]
    pub stitches: Vec<Vec<serde_json::Value>>,
    /// Panel order, when given.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub panel_order: Option<Vec<String>>,
}

/// One panel: a flat outline placed in 3D.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct PanelJson {
    /// Translation of the panel's origin, pattern units.
    pub translation: [f64; 3],
    /// Rotation, Euler degrees, R = Rz Ry Rx.
    pub rotation: [f64; 3],
    /// 2D outline corners, pattern units.
    pub vertices: Vec<[f64; 2]>,
    /// Edges in loop order.
    pub edges: Vec<EdgeJson>,
}

/// One edge of a panel outline.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct EdgeJson {
    /// Start and end corner.
    pub endpoints: [usize; 2],
    /// Curvature: absent for a straight edge.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub curvature: Option<serde_json::Value>,
    /// Free-form label (e.g. a collar or an interface), kept as vertex labels.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub label: Option<String>,
}
