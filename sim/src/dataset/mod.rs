//! Dataset synthesis, the engine's main job: a TOML spec of garments, motions, shapes and
//! materials becomes a reproducible list of sequences (stable ids and seeds, training and test
//! splits), each judged by quality gates and recorded in a JSON Lines manifest.
//!
//! Running the sequences (files, parallelism, shards, resume) is the command line's part; this
//! module is the plain data: [`DatasetSpec`], [`plan`], [`ManifestRecord`], [`GateResult`].

mod manifest;
mod plan;
mod spec;

pub use manifest::{Attempt, GateResult, ManifestRecord, stats};
pub use plan::{PlannedSequence, SPLITS, derive_seed, expand_motions, plan};
pub use spec::{
    DatasetSpec, GarmentEntry, GateSpec, MaterialRanges, MotionEntry, SequenceSpec, SolverSpec,
    SplitSpec, Tag,
};
