//! Checkpoints for resume: `RUN/checkpoint-<step>/` holds the model, the AdamW state and the EMA
//! (burnpack, which keeps the parameter ids the optimizer state is keyed by; safetensors would
//! silently restart AdamW), the configuration and the run's counters. A checkpoint is written
//! under a temporary name and renamed, then `RUN/checkpoint.json` is pointed at it, so a run
//! killed at any moment resumes from the last whole checkpoint.

use std::path::{Path, PathBuf};

use burn::optim::{AdamWConfig, ModuleOptimizer};
use burn::prelude::*;
use serde::{Deserialize, Serialize};

use crate::error::{Result, file_error};
use crate::model::Dit;
use crate::run::{RunConfig, TrainConfig};
use files::{sha256_hex, write_atomic};

/// The counters a resumed run continues from.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct RunState {
    /// Steps done.
    pub step: usize,
    /// Wall time of all sessions so far, s.
    pub wall_s: f64,
    /// Lowest validation loss so far.
    pub best_val_loss: Option<f64>,
    /// The step of that loss, whose EMA weights `RUN/best.safetensors` holds (absent in
    /// checkpoints written before the file was).
    #[serde(default)]
    pub best_val_step: Option<usize>,
}

/// `RUN/checkpoint.json`.
#[derive(Debug, Clone, Serialize, Deserialize)]
struct Pointer {
    step: usize,
    dir: String,
}

/// AdamW as the run's configuration sets it (eps and weight decay explicit: burn's defaults
/// are not PyTorch's).
pub fn optimizer(training: &TrainConfig) -> ModuleOptimizer {
    AdamWConfig::new()
        .with_beta_1(training.beta1 as f32)
        .with_beta_2(training.beta2 as f32)
        .with_epsilon(training.adam_eps as f32)
        .with_weight_decay(training.weight_decay as f32)
        .init()
}

/// The weight files of a checkpoint.
const CHECKPOINT_FILES: [&str; 3] = ["model.bpk", "optim.bpk", "ema.bpk"];
/// The files of [`CHECKPOINT_FILES`] that hold the whole network (AdamW's state may be empty).
const NETWORK_FILES: [&str; 2] = ["model.bpk", "ema.bpk"];
/// The SHA-256 of each, written with them (`{"model.bpk": "<hex>", ...}`).
const CHECKSUMS: &str = "checksums.json";

/// Checks a checkpoint's weight files before burn reads them: regular files of a plausible
/// size, model and EMA files large enough for the configuration's network (so a damaged
/// file, or the checkpoint of a far smaller model, is refused before that network is
/// allocated), and the SHA-256 each was written with (`checksums.json`). A checkpoint without
/// checksums is refused: burn's optimizer reader panics on a foreign record (a tensor without
/// a parameter id, found by the `checkpoint` fuzz target), so only files this program wrote
/// may reach it.
fn verify_files(dir: &Path, config: &RunConfig) -> Result<()> {
    // The network's weights, every parameter as F32; AdamW's state may be empty at step 0.
    let parameters = config.model.parameter_count();
    let needed = 4 * parameters as u64;
    for file in CHECKPOINT_FILES {
        let path = dir.join(file);
        let bytes = crate::run::check_weights_file(&path)?;
        if NETWORK_FILES.contains(&file) && bytes < needed {
            return Err(file_error(
                &path,
                format!(
                    "damaged or of another model: {bytes} bytes, and the configuration's \
                     network of {parameters} parameters needs at least {needed}"
                ),
            ));
        }
    }
    let path = dir.join(CHECKSUMS);
    if !path.exists() {
        return Err(file_error(
            &path,
            "missing: a checkpoint is resumed only with the checksums it was written with \
             (checkpoints written before 2026-12-02 have none; start the run again)",
        ));
    }
    let text = files::read_to_string(&path, files::limits::TEXT, "checkpoint checksums")?;
    let sums: std::collections::BTreeMap<String, String> =
        serde_json::from_str(&text).map_err(|e| file_error(&path, format!("damaged: {e}")))?;
    for file in CHECKPOINT_FILES {
        let file_path = dir.join(file);
        let bytes = files::read(&file_path, files::limits::TENSORS, "weights file")?;
        if sums.get(file) != Some(&sha256_hex(&bytes)) {
            return Err(file_error(
                &file_path,
                format!("damaged: its SHA-256 is not the one in {CHECKSUMS}"),
            ));
        }
    }
    Ok(())
}

/// Saves a checkpoint of `state.step` and removes older ones.
pub fn save(
    run: &Path,
    config: &RunConfig,
    model: &Dit,
    optim: &ModuleOptimizer,
    ema: &Dit,
    state: &RunState,
) -> Result<()> {
    let name = format!("checkpoint-{:08}", state.step);
    let dir = run.join(&name);
    let temporary = files::Temporary::create_dir(&dir)?;
    let tmp = temporary.path().to_path_buf();
    let fail = |file: &str, e: &dyn std::fmt::Display| file_error(&tmp.join(file), e.to_string());
    model
        .clone()
        .save_file(tmp.join("model.bpk"))
        .map_err(|e| fail("model.bpk", &e))?;
    optim
        .save(tmp.join("optim.bpk"))
        .map_err(|e| fail("optim.bpk", &e))?;
    ema.clone()
        .save_file(tmp.join("ema.bpk"))
        .map_err(|e| fail("ema.bpk", &e))?;
    // burnpack has no checksum: a flipped byte in a weight would load silently.
    let mut checksums = std::collections::BTreeMap::new();
    for file in CHECKPOINT_FILES {
        let bytes = std::fs::read(tmp.join(file)).map_err(|e| fail(file, &e))?;
        checksums.insert(file.to_string(), sha256_hex(&bytes));
    }
    let json = serde_json::to_vec_pretty(&checksums).expect("checksums serialize");
    std::fs::write(tmp.join(CHECKSUMS), json).map_err(|e| fail(CHECKSUMS, &e))?;
    std::fs::write(tmp.join("config.toml"), config.to_toml())
        .map_err(|e| fail("config.toml", &e))?;
    let json = serde_json::to_vec_pretty(state).expect("the run state serializes");
    std::fs::write(tmp.join("state.json"), json).map_err(|e| fail("state.json", &e))?;
    let _ = std::fs::remove_dir_all(&dir);
    temporary.persist()?;
    let pointer = Pointer {
        step: state.step,
        dir: name.clone(),
    };
    write_atomic(
        &run.join("checkpoint.json"),
        &serde_json::to_vec_pretty(&pointer).expect("the pointer serializes"),
    )?;
    for old in checkpoint_dirs(run) {
        if old.file_name().and_then(|n| n.to_str()) != Some(name.as_str()) {
            let _ = std::fs::remove_dir_all(old);
        }
    }
    Ok(())
}

fn checkpoint_dirs(run: &Path) -> Vec<PathBuf> {
    let Ok(entries) = std::fs::read_dir(run) else {
        return Vec::new();
    };
    entries
        .flatten()
        .map(|e| e.path())
        .filter(|p| {
            p.is_dir()
                && p.file_name()
                    .and_then(|n| n.to_str())
                    .is_some_and(|n| n.starts_with("checkpoint-") || n.starts_with(".checkpoint-"))
        })
        .collect()
}

/// A loaded checkpoint: the model (on the autodiff device), its optimizer, the EMA (plain) and
/// the counters.
pub struct Loaded {
    /// Trainable model.
    pub model: Dit,
    /// AdamW with its moments.
    pub optim: ModuleOptimizer,
    /// EMA weights.
    pub ema: Dit,
    /// Counters.
    pub state: RunState,
}

/// The checkpoint folder a resume of `run` would continue from and its step, checked against `config`
/// without loading any weights, so a resume that cannot continue is refused before anything
/// is written. `None` for a run that never reached a checkpoint and never finished (it starts
/// again); a finished model without `checkpoint.json` (the shipped ones), or checkpoint folders
/// without it, is refused: resuming would retrain and replace it.
pub fn resumable(run: &Path, config: &RunConfig) -> Result<Option<(PathBuf, usize)>> {
    let pointer_path = run.join("checkpoint.json");
    if !pointer_path.exists() {
        let finished = run.join("model.safetensors").exists();
        let orphans = std::fs::read_dir(run).ok().is_some_and(|entries| {
            entries
                .flatten()
                .any(|e| e.file_name().to_string_lossy().starts_with("checkpoint-"))
        });
        if finished || orphans {
            let what = if finished {
                "a finished model without checkpoints"
            } else {
                "checkpoint folders without the checkpoint.json that names the last"
            };
            return Err(file_error(
                run,
                format!("holds {what}: --resume cannot continue it (train into a new folder)"),
            ));
        }
        return Ok(None);
    }
    let text = files::read_to_string(&pointer_path, files::limits::TEXT, "checkpoint pointer")?;
    let pointer: Pointer = serde_json::from_str(&text)
        .map_err(|e| file_error(&pointer_path, format!("damaged: {e}")))?;
    if !pointer.dir.starts_with("checkpoint-") || pointer.dir.contains(['/', '\\']) {
        return Err(file_error(
            &pointer_path,
            format!("damaged: '{}' is not a checkpoint folder name", pointer.dir),
        ));
    }
    let dir = run.join(&pointer.dir);
    let saved_path = dir.join("config.toml");
    let saved = RunConfig::load_saved(&saved_path)?;
    if let Some(difference) = config.resume_difference(&saved) {
        return Err(file_error(
            &saved_path,
            format!(
                "the checkpoint was made with another configuration ({difference}); resume with the run's own configuration or train into a new folder"
            ),
        ));
    }
    Ok(Some((dir, pointer.step)))
}

/// The run's last checkpoint, or `None` when it has none yet. A checkpoint of another
/// configuration, or a damaged one, is an error naming the file.
pub fn load(run: &Path, config: &RunConfig, device: &Device) -> Result<Option<Loaded>> {
    let Some((dir, step)) = resumable(run, config)? else {
        return Ok(None);
    };
    let damaged = |file: &str, e: &dyn std::fmt::Display| {
        file_error(&dir.join(file), format!("damaged or of another model: {e}"))
    };
    verify_files(&dir, config)?;
    let model = Dit::new(&config.model, device)
        .try_load_file(dir.join("model.bpk"))
        .map_err(|e| damaged("model.bpk", &e))?;
    let optim = optimizer(&config.training)
        .load(dir.join("optim.bpk"))
        .map_err(|e| damaged("optim.bpk", &e))?;
    let ema = Dit::new(&config.model, &device.clone().inner())
        .try_load_file(dir.join("ema.bpk"))
        .map_err(|e| damaged("ema.bpk", &e))?;
    let state_path = dir.join("state.json");
    let text = files::read_to_string(&state_path, files::limits::TEXT, "run state")?;
    let state: RunState = serde_json::from_str(&text)
        .map_err(|e| file_error(&state_path, format!("damaged: {e}")))?;
    if state.step != step {
        return Err(file_error(&state_path, "does not match checkpoint.json"));
    }
    Ok(Some(Loaded {
        model,
        optim,
        ema,
        state,
    }))
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A checkpoint whose weight files are far smaller than its configuration's network
    /// (damaged, or of another model) is refused by name before that network is built; under
    /// its own configuration it loads.
    #[test]
    fn weights_too_small_for_the_configuration_are_refused_before_building() {
        let run = tempfile::tempdir().unwrap();
        let device = Device::flex().autodiff();
        let small = RunConfig {
            model: crate::model::tests::tiny(),
            ..RunConfig::default()
        };
        let model = Dit::new(&small.model, &device);
        let ema = Dit::new(&small.model, &device.clone().inner());
        let optim = optimizer(&small.training);
        let state = RunState {
            step: 10,
            wall_s: 1.0,
            best_val_loss: None,
            best_val_step: None,
        };
        let mut large = small.clone();
        large.model.width = 2048;
        save(run.path(), &large, &model, &optim, &ema, &state).unwrap();
        let Err(err) = load(run.path(), &large, &device) else {
            panic!("a checkpoint of 16-wide weights loaded as a 2048-wide network");
        };
        let message = err.to_string();
        assert!(
            message.contains("model.bpk") && message.contains("needs at least"),
            "{message}"
        );

        save(run.path(), &small, &model, &optim, &ema, &state).unwrap();
        let loaded = load(run.path(), &small, &device).unwrap().unwrap();
        assert_eq!(loaded.state, state);
    }
}
