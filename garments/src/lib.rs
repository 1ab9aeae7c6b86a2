//! Garment templates for the engine and the surrogate (not yet implemented; see the garments
//! issue).
//!
//! This crate will hold the garment mesh type (positions, triangles, per-corner UVs, panel
//! labels) with OBJ/PLY import and export and validation, the GarmentCode sewing-pattern importer
//! that meshes, stitches and UV-maps panels into templates draped on the default body in its
//! canonical A-pose, and the built-in parametric design library.
