//! The shipped model inside the wheel: the ensemble and both of its networks are compiled into
//! the module and unpacked once into the cache folder (content-addressed), so an installed
//! package predicts with `model="builtin"` wherever it is, without the source tree.

use std::path::PathBuf;

use pyo3::PyResult;
use sha2::{Digest, Sha256};

use crate::errors::{file_error, surrogate_error};

macro_rules! shipped {
    ($($path:literal),* $(,)?) => {
        [$(($path, include_bytes!(concat!("../../surrogate/", $path)) as &[u8])),*]
    };
}

/// Every file the shipped model is loaded from, by its path under `surrogate/`.
const SHIPPED: [(&str, &[u8]); 7] = shipped![
    "ensemble/ensemble.toml",
    "weights/config.toml",
    "weights/model.safetensors",
    "weights/tensors.json",
    "weights-seed1/config.toml",
    "weights-seed1/model.safetensors",
    "weights-seed1/tensors.json",
];

/// The folder the shipped model is unpacked into (once; a file that marks it complete is
/// written last, so an interrupted unpack is done again).
fn unpacked() -> PyResult<PathBuf> {
    let mut hash = Sha256::new();
    for (path, bytes) in SHIPPED {
        hash.update(path.as_bytes());
        hash.update(bytes);
    }
    let hex: String = hash.finalize()[..8]
        .iter()
        .map(|b| format!("{b:02x}"))
        .collect();
    let dir = sim::templates::cache_dir()
        .join("models")
        .join(format!("builtin-{hex}"));
    let complete = dir.join("complete");
    if !complete.is_file() {
        for (path, bytes) in SHIPPED {
            let file = dir.join(path);
            files::create_folder_of(&file).map_err(file_error)?;
            files::write_atomic(&file, bytes).map_err(file_error)?;
        }
        files::write_atomic(&complete, b"").map_err(file_error)?;
    }
    Ok(dir)
}

/// The folder a model name stands for: `builtin` (the shipped ensemble), `builtin-single`
/// (its first network), else a run or ensemble folder, as on the command line.
pub fn model_dir(name: &str) -> PyResult<PathBuf> {
    match name {
        "builtin" => Ok(unpacked()?.join("ensemble")),
        "builtin-single" => Ok(unpacked()?.join("weights")),
        _ => surrogate::run::model_dir(name).map_err(surrogate_error),
    }
}
