//! A run's weights: `model.safetensors` (the EMA weights under the names PyTorch users
//! expect: a Linear's weight is `[out, in]`), written by training and loaded back for
//! sampling, checked against the run's `config.toml` and `tensors.json`.

use std::path::Path;

use burn::prelude::*;
use burn::store::{BurnToPyTorchAdapter, ModuleSnapshot, PyTorchToBurnAdapter, SafetensorsStore};

use super::config::RunConfig;
use crate::data::TensorManifest;
use crate::error::{Result, file_error};
use crate::model::Dit;

/// The commit this build was made from (`unknown` outside a git checkout).
pub const COMMIT: &str = env!("DIT_GARMENT_COMMIT");

/// Where a `model.safetensors` came from, kept in its header's metadata (the string map every
/// safetensors reader shows), so weights found alone still name what made them.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Provenance {
    /// SHA-256 of the run's `config.toml`.
    pub config_sha256: String,
    /// SHA-256 of the `manifest.json` of the training tensors (which holds every shard's
    /// checksum and the datasets they were made from).
    pub dataset_manifest_sha256: String,
    /// The commit of the program that trained it.
    pub commit: String,
}

impl Provenance {
    /// The metadata keys, in the order written.
    pub const KEYS: [&'static str; 3] = ["config_sha256", "dataset_manifest_sha256", "commit"];

    fn values(&self) -> [&str; 3] {
        [
            &self.config_sha256,
            &self.dataset_manifest_sha256,
            &self.commit,
        ]
    }

    /// The provenance in the header of `path`; `None` for weights saved without one (the
    /// models shipped before 2026-12-05).
    pub fn read(path: &Path) -> Result<Option<Provenance>> {
        let bytes = files::read(path, files::limits::TENSORS, "weights file")?;
        let (_, header) =
            safetensors::SafeTensors::read_metadata(&bytes).map_err(|e| file_error(path, e))?;
        let Some(map) = header.metadata() else {
            return Ok(None);
        };
        let get = |key: &str| map.get(key).cloned();
        Ok(
            match (
                get("config_sha256"),
                get("dataset_manifest_sha256"),
                get("commit"),
            ) {
                (Some(config_sha256), Some(dataset_manifest_sha256), Some(commit)) => {
                    Some(Provenance {
                        config_sha256,
                        dataset_manifest_sha256,
                        commit,
                    })
                }
                _ => None,
            },
        )
    }
}

/// Writes `model` to `path` (safetensors, PyTorch names) with its provenance in the header's
/// metadata, through a temporary name.
pub fn save_weights(model: &Dit, path: &Path, provenance: &Provenance) -> Result<()> {
    let (temporary, file) = files::Temporary::create(path)?;
    drop(file);
    let tmp = temporary.path().to_path_buf();
    let mut store = SafetensorsStore::from_file(&tmp)
        .overwrite(true)
        .with_to_adapter(BurnToPyTorchAdapter);
    for (key, value) in Provenance::KEYS.into_iter().zip(provenance.values()) {
        store = store.metadata(key, value);
    }
    model
        .save_into(&mut store)
        .map_err(|e| file_error(&tmp, e))?;
    // burn-store creates the file readable by its owner only; weights are meant to be shared.
    #[cfg(unix)]
    {
        use std::os::unix::fs::PermissionsExt;
        std::fs::set_permissions(&tmp, std::fs::Permissions::from_mode(0o644))
            .map_err(|e| file_error(&tmp, e))?;
    }
    Ok(temporary.persist()?)
}

/// The model of a run folder: `RUN/config.toml` and `RUN/model.safetensors`, on `device`.
/// Weights that do not fit the configuration (missing, extra or of another shape) are an
/// error naming the file, never a silent partial load.
pub fn load_run(run: &Path, device: &Device) -> Result<(RunConfig, Dit)> {
    let config_path = run.join("config.toml");
    let config = RunConfig::load_saved(&config_path)?;
    config.validate().map_err(|e| file_error(&config_path, e))?;
    let weights = run.join("model.safetensors");
    let model = load_weights(&weights, &config, &config_path, device)?;
    Ok((config, model))
}

/// The network of `config` with the weights in `weights` (a run's `model.safetensors` or
/// `best.safetensors`; `config_path` names the configuration in errors), refused whole where
/// they do not fit.
pub fn load_weights(
    weights: &Path,
    config: &RunConfig,
    config_path: &Path,
    device: &Device,
) -> Result<Dit> {
    if !weights.exists() {
        // A link to nothing (or a loop of links) is there, just not readable.
        let problem = match weights.symlink_metadata() {
            Ok(_) => "a link that leads to no file (or a loop of links)",
            Err(_) => "missing (train the model first)",
        };
        return Err(file_error(weights, problem));
    }
    // Counted before the network is built, so the weights of a far larger network are
    // refused without allocating it.
    let (values, expected) = (
        check_model_weights(weights)?,
        config.model.parameter_count(),
    );
    if values != expected {
        return Err(file_error(
            weights,
            format!(
                "does not fit {}: it holds {values} values, that network has {expected} \
                 parameters (the weights of another model)",
                config_path.display()
            ),
        ));
    }
    let mut model = Dit::new(&config.model, device);
    let mut store = SafetensorsStore::from_file(weights).with_from_adapter(PyTorchToBurnAdapter);
    let result = model.load_from(&mut store).map_err(|e| {
        file_error(
            weights,
            format!(
                "does not fit {} (damaged, or the weights of another model): {e}",
                config_path.display()
            ),
        )
    })?;
    if !result.is_success() || !result.missing.is_empty() || !result.unused.is_empty() {
        return Err(file_error(
            weights,
            format!("does not fit {}: {result}", config_path.display()),
        ));
    }
    Ok(model)
}

/// The run file holding the manifest of the tensors a model was trained on.
pub const TENSORS_MANIFEST: &str = "tensors.json";

/// A trained model ready to sample: its configuration, its EMA weights and the manifest of
/// the tensors it was trained on (normalization, condition layout, target, templates).
#[derive(Debug, Clone)]
pub struct TrainedModel {
    /// The run folder.
    pub run: std::path::PathBuf,
    /// `config.toml`.
    pub config: RunConfig,
    /// The network with the EMA weights.
    pub model: Dit,
    /// Further networks whose outputs are averaged with `model`'s: the other members of an
    /// ensemble folder; empty for a run folder.
    pub members: Vec<Dit>,
    /// The run folder of each network, `model`'s first, then the `members`'.
    pub networks: Vec<std::path::PathBuf>,
    /// `tensors.json`.
    pub data: TensorManifest,
    /// The device the network was loaded on, which sampling runs on.
    pub device: Device,
}

impl TrainedModel {
    /// Loads a run folder (see [`load_run`]) and its `tensors.json`, checked against the
    /// configuration. An ensemble folder is loaded by [`TrainedModel::load`].
    pub fn load_run_folder(run: &Path, device: &Device) -> Result<Self> {
        let (config, model) = load_run(run, device)?;
        let path = run.join(TENSORS_MANIFEST);
        let text = files::read_to_string(&path, files::limits::TEXT, "tensors manifest")?;
        let data: TensorManifest = serde_json::from_str(&text).map_err(|e| file_error(&path, e))?;
        if let Some(problem) = data.statistics_problem() {
            return Err(file_error(&path, problem));
        }
        let m = &config.model;
        let problem = if data.resolution != m.resolution {
            Some(format!(
                "resolution {} here, {} in config.toml",
                data.resolution, m.resolution
            ))
        } else if data.condition_dim != m.condition_dim {
            Some(format!(
                "condition_dim {} here, {} in config.toml",
                data.condition_dim, m.condition_dim
            ))
        } else if data.target != m.target {
            Some(format!(
                "target {} here, {} in config.toml",
                data.target.name(),
                m.target.name()
            ))
        } else if !data.normalization_fits() {
            Some("normalization statistics of the wrong length".into())
        } else if m.body_channels() > data.body_channels() {
            Some(format!(
                "the model takes {} body input channels and these tensors have {}",
                m.body_channels(),
                data.body_channels()
            ))
        } else {
            None
        };
        if let Some(problem) = problem {
            return Err(file_error(
                &path,
                format!("does not fit the model: {problem}"),
            ));
        }
        Ok(Self {
            run: run.to_path_buf(),
            config,
            model,
            members: Vec::new(),
            networks: vec![run.to_path_buf()],
            data,
            device: device.clone(),
        })
    }
}

/// The largest weight magnitude a trained network holds here (the shipped ones stay under 1);
/// beyond it a file is damaged or not a trained network, and sampling would overflow.
pub const MAX_WEIGHT: f32 = 1e4;

/// Refuses a weights file that is not a regular file (a FIFO would block the reader, a
/// device never end) or is larger than any model, before burn reads it; returns its size in
/// bytes.
pub(crate) fn check_weights_file(path: &Path) -> Result<u64> {
    let (_, bytes) = files::open_bounded(path, files::limits::TENSORS, "weights file")?;
    Ok(bytes)
}

/// Refuses, before burn reads it, a `model.safetensors` that [`check_weights_file`] refuses,
/// that is not safetensors, or that holds a tensor that is not F32 (burn loads F16 or F64 and
/// then panics in the first matrix product) or a value that is not finite or beyond
/// [`MAX_WEIGHT`]; the error names the tensor. Returns how many values the tensors hold.
fn check_model_weights(path: &Path) -> Result<usize> {
    let bytes = files::read(path, files::limits::TENSORS, "weights file")?;
    let tensors = safetensors::SafeTensors::deserialize(&bytes)
        .map_err(|e| file_error(path, format!("not a safetensors file: {e}")))?;
    let mut values = 0;
    for (name, view) in tensors.tensors() {
        if view.dtype() != safetensors::Dtype::F32 {
            return Err(file_error(
                path,
                format!(
                    "tensor '{name}' is {:?}; the model's weights are F32",
                    view.dtype()
                ),
            ));
        }
        let bad = view
            .data()
            .chunks_exact(4)
            .map(|b| f32::from_le_bytes([b[0], b[1], b[2], b[3]]))
            .find(|v| !(v.is_finite() && v.abs() <= MAX_WEIGHT));
        if let Some(v) = bad {
            return Err(file_error(
                path,
                format!(
                    "tensor '{name}' holds {v}: a trained network's weights are finite and \
                     within {MAX_WEIGHT:e}"
                ),
            ));
        }
        values += view.data().len() / 4;
    }
    Ok(values)
}
