//! Garment templates for the engine and the surrogate: the garment mesh type (positions,
//! triangles, per-corner UVs, panels and vertex labels), OBJ import and export with groups,
//! PLY export, validation with documented repairs, GarmentCode sewing patterns (parsed,
//! meshed with constrained Delaunay refinement, stitched, UV-packed), the parametric design
//! library, and the built-in skirt.
//!
//! A template is aligned to the body in its canonical A-pose (betas = 0, no root translation):
//! its positions are where the garment rests on that body. Draping a sewn pattern into a
//! template is a simulation, done by `sim::sewing`.
#![warn(missing_docs)]

mod builtin;
mod check;
mod error;
mod import;
pub mod library;
mod mesh;
mod obj;
pub mod pattern;
mod unwrap;

pub use builtin::{BUILTIN, SkirtParams, builtin_names, skirt};
pub use check::{
    CheckReport, FileCheck, Finding, MAX_EXTENT_M, MAX_TEMPLATE_VERTICES, MIN_EXTENT_M, check,
    check_numbered, check_obj_file, repair, repair_numbered,
};
pub use error::{Error, Result};
pub use import::{median_edge_length, parse_ply, read_mesh, subdivide, uv_overlap, weld};
pub use mesh::{Garment, vertex_neighbours};
pub use obj::{parse_obj, read_obj, read_obj_numbered, write_mesh_obj, write_obj, write_ply};
pub use pattern::{Pattern, SewnMesh, joined_roots};
pub use unwrap::{MAX_CHART_ANGLE_DEG, PanelGuide, unwrap_uvs};
