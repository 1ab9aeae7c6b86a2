//! The ground-truth engine (not yet implemented; see the engine issue).
//!
//! This crate will hold the velocity-level projective-dynamics cloth solver with exact
//! Signorini-Coulomb frictional contact against animated bodies, ground and props; seams and
//! attachments; the scene runner; MCAP recordings; quality gates and physical energies.
