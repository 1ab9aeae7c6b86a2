//! The model folder `--model` names (`builtin`: the weights shipped in the repository), shared
//! by `predict`, `demo` and `evaluate`.

use std::path::{Path, PathBuf};

use anyhow::{Result, bail};

/// Where `--model builtin` looks: the weights shipped in the repository.
pub fn builtin_dir() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("surrogate/weights")
}

/// The run folder `--model` names (`builtin` or a folder).
pub fn model_dir(name: &str) -> Result<PathBuf> {
    if name == "builtin" {
        let dir = builtin_dir();
        if !dir.join("model.safetensors").is_file() {
            bail!(
                "no built-in model: {} holds no model.safetensors (this build ships none); \
                 train one (`dit-garment train`) and pass --model RUN",
                dir.display()
            );
        }
        return Ok(dir);
    }
    let dir = PathBuf::from(name);
    if !dir.is_dir() {
        bail!("--model {name}: not a run folder (or `builtin`)");
    }
    Ok(dir)
}
