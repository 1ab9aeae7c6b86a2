//! A trained run as training leaves it and sampling reads it: `config.toml` (the network and
//! its training, [`RunConfig`]), `model.safetensors` (the EMA weights) and `tensors.json` (the
//! manifest of the tensors trained on: normalization, condition layout, target, templates),
//! loaded together as a [`TrainedModel`]; an ensemble folder names several such runs whose
//! outputs are averaged. Training writes runs (`train`); prediction and evaluation only read
//! them, so neither depends on training.

mod config;
mod ensemble;
mod weights;

use std::path::{Path, PathBuf};

pub use config::{Objective, RunConfig, TimeSampling, TrainConfig};
pub use ensemble::ENSEMBLE_FILE;
pub(crate) use weights::check_weights_file;
pub use weights::{TENSORS_MANIFEST, TrainedModel, load_run, save_weights};

use crate::error::{Error, Result};

/// The weights shipped in the repository, which `--model builtin` names.
pub fn builtin_dir() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("weights")
}

/// The shipped ensemble, which `--model builtin-pair` names: the built-in model and the same
/// recipe trained with another seed, averaged (more accurate, at two network calls a frame).
pub fn builtin_pair_dir() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("ensemble")
}

/// The folder a model name stands for: `builtin` (the shipped weights), `builtin-pair` (the
/// shipped ensemble), a run folder or an ensemble folder.
pub fn model_dir(name: &str) -> Result<PathBuf> {
    if name == "builtin-pair" {
        return Ok(builtin_pair_dir());
    }
    if name == "builtin" {
        let dir = builtin_dir();
        if !dir.join("model.safetensors").is_file() {
            return Err(Error::Config {
                path: dir.display().to_string(),
                message: "no built-in model: this build ships no model.safetensors; train one \
                          (`dit-garment train`) and pass --model RUN"
                    .into(),
            });
        }
        return Ok(dir);
    }
    let dir = PathBuf::from(name);
    if !dir.is_dir() {
        return Err(Error::Config {
            path: name.to_string(),
            message: "not a run or ensemble folder (or `builtin`, `builtin-pair`)".into(),
        });
    }
    Ok(dir)
}
