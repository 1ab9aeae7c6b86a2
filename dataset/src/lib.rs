//! Dataset synthesis, the engine's main job, as a crate of its own over the engine's public API: a TOML spec of garments, motions, shapes and
//! materials becomes a reproducible list of sequences (stable ids and seeds, training and test
//! splits), each judged by quality gates and recorded in a JSON Lines manifest.
//!
//! This module is the plain data ([`DatasetSpec`], [`plan`], [`ManifestRecord`],
//! [`GateResult`]), the folder's layout ([`DatasetDir`], [`finished_record`]), running one
//! sequence with its retries and gates ([`Synthesis`]) and verification ([`verify`]). Which
//! sequences a process runs (shards) and in how many threads is the command line's part.

mod dir;
mod error;
mod manifest;
mod merge;
mod plan;
mod shard;
mod spec;
mod split;
mod stats;
mod synth;
mod verify;

pub use dir::{DatasetDir, finished_record, split_finished};
pub use error::{Error, Result};
pub use manifest::{Attempt, GateResult, ManifestRecord, RecordPathError};
pub use merge::merge;
pub use plan::{PlannedSequence, derive_seed, expand_motions, plan};
pub use shard::Shard;
pub use spec::{
    DatasetSpec, GarmentEntry, GateSpec, MaterialRanges, MotionEntry, SequenceSpec, SolverSpec,
    SplitSpec, Tag,
};
pub use split::{Split, Status};
pub use stats::{Histogram, Stats, stats};
pub use synth::{Synthesis, Template, make_templates};
pub use verify::{Verification, load, verify};
