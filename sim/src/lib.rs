//! The ground-truth engine: velocity-level projective dynamics (edge springs, Laplacian
//! bending, lumped mass, seams, attachments, pins) with exact Signorini-Coulomb frictional
//! contact against animated bodies and props, after Ly, Jouve, Boissieux and
//! Bertails-Descoubes, "Projective Dynamics with Dry Frictional Contact" (2020).
//!
//! Data: a [`ClothMesh`] and [`Material`] make a [`ClothSetup`]; a [`Solver`] holds its
//! factorized global matrix and advances a [`ClothState`] against [`obstacles::Obstacles`].
//! A garment sequence is a [`SceneConfig`] (plain data, TOML) resolved into a
//! [`scene::Scene`], run frame by frame and written by [`recording::SequenceWriter`]. Units
//! are SI, y is up.
#![warn(missing_docs)]

mod cloth;
pub mod config;
pub mod constraints;
mod contact;
mod error;
mod factor;
pub mod metrics;
pub mod obstacles;
mod params;
pub mod recording;
pub mod run;
pub mod scene;
mod self_contact;
mod self_intersection;
pub mod sewing;
mod solver;
pub mod sources;
mod spin_join;
mod system;
pub mod templates;
mod untangle;
pub mod unwind;

pub use cloth::{ClothMesh, ClothState, Vec3};
pub use config::{SceneConfig, ValidSceneConfig};
pub use constraints::{Attachment, BendingRest, Seam, Spring};
pub use contact::Contact;
pub use error::{BlowUpCause, Error, MeshError, Result};
pub use params::{Material, SolverParams};
pub use self_intersection::{count_self_intersections, self_intersecting_pairs};
pub use solver::{ClothSetup, FrameReport, Solver, Stage, StageTimes, StepReport};
pub use system::Symbolic;
pub use untangle::{UntangleReport, untangle};

/// Bumped whenever a change to the engine changes what it computes, so templates draped and
/// cached by an older engine are made again.
pub const ENGINE_REVISION: u32 = 4;
