//! The learned surrogate, DiT-Garment: UV geometry images of garment templates (atlas,
//! encode, chart-aware readback and its transpose), the canonical frame, the two training
//! targets (`displacement` and `lbs_residual`), the condition vector, and the training
//! tensors a dataset becomes (`geometry`, `data`); the diffusion transformer (`model`), its
//! training with rectified flow (`train`) and the flow maths training and sampling share
//! (`flow`: interpolation, targets, x0 <-> velocity, the time grid, the Euler sampler), the
//! trained run folder (`run`) and the prediction of whole sequences with intersection guidance
//! (`predict`), which reads runs and never depends on training.
//!
//! Depends on `sim` for recordings and materials as plain data, never on the scene runner.
#![warn(missing_docs)]

pub mod data;
mod error;
pub mod evaluate;
pub mod flow;
pub mod geometry;
pub mod import;
pub mod model;
pub mod noise;
pub mod predict;
pub mod run;
pub mod train;

/// The burn version the model is written for, for callers that build inputs.
pub use burn;
pub use error::{Error, Result};

/// burn's flex backend draws every random tensor from one global generator, so tests that
/// seed it and draw from it run one at a time: interleaved with another test's draws (the
/// harness runs tests in parallel) a seeded test would see other numbers on every run.
#[cfg(test)]
pub(crate) fn seeded(
    device: &burn::prelude::Device,
    seed: u64,
) -> std::sync::MutexGuard<'static, ()> {
    static RANDOM: std::sync::Mutex<()> = std::sync::Mutex::new(());
    let guard = RANDOM.lock().unwrap_or_else(|e| e.into_inner());
    device.seed(seed);
    guard
}
