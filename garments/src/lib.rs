//! Garment templates for the engine and the surrogate: the garment mesh type (positions,
//! triangles and per-corner UVs), OBJ import and export, and the built-in garments.
//!
//! A template is aligned to the body in its canonical A-pose (betas = 0, no root translation):
//! its positions are where the garment rests on that body.
#![warn(missing_docs)]

mod builtin;
mod error;
mod mesh;
mod obj;

pub use builtin::{BUILTIN, SkirtParams, builtin_names, skirt};
pub use error::{Error, Result};
pub use mesh::Garment;
pub use obj::{read_obj, write_obj};
