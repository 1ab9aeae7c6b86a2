//! What a model learns from: the condition vector of a frame (`conditions.rs`), recorded
//! sequences with their UV round-trip floor (`sequence.rs`), and a dataset as training tensors
//! (`tensors.rs`, described by its `manifest.json`: `manifest.rs`).

mod conditions;
mod frames;
mod history;
mod manifest;
mod mirror;
mod previous;
mod sequence;
mod shards;
mod stats;
mod tensors;

pub use conditions::{
    Block, BlockScaling, CONDITION_JOINTS, ConditionLayout, ConditionScaling, VELOCITIES,
};
pub use frames::{Frames, TrainingTensors};
pub use history::{HISTORY_SECONDS, HISTORY_VALUES, pose_history};
pub use manifest::{
    Normalization, ShardInfo, SplitInfo, TENSORS_FORMAT, TemplateInfo, TensorManifest,
};
pub use mirror::{
    DEFAULT_MIRROR_MAX_GAP_M, MAX_BODY_ASYMMETRY_M, TemplateMirror, body_asymmetry_m,
};
pub use previous::previous_state_map;
pub use sequence::{Floor, Sequence, roundtrip_floor};
pub use stats::Stats;
pub(crate) use tensors::channels_first;
pub use tensors::{TensorOptions, body_input_maps, write_tensors};
