//! What a model learns from: the condition vector of a frame (`conditions.rs`).

mod conditions;

pub use conditions::{Block, CONDITION_JOINTS, ConditionLayout, MaterialRanges};
