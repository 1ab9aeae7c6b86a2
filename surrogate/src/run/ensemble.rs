//! An ensemble folder: `ensemble.toml` naming two or more run folders trained on the same
//! tensors, loaded as one [`TrainedModel`] whose sampler averages the networks' outputs
//! before guidance. Two models of one recipe trained with different seeds err differently,
//! and their mean is closer to the truth than either (docs/SURROGATE_ARMS.md, "An ensemble in the
//! product"), at one network call per member.
//!
//! ```toml
//! # ENSEMBLE/ensemble.toml: members relative to this folder (or absolute)
//! members = ["../runs/seed0", "../runs/seed1"]
//! ```

use std::path::{Path, PathBuf};

use burn::prelude::*;
use serde::Deserialize;

use super::weights::TrainedModel;
use crate::error::{Result, file_error};

/// The file that makes a folder an ensemble.
pub const ENSEMBLE_FILE: &str = "ensemble.toml";

/// The most networks an ensemble averages: each costs a network call per frame, and past a
/// few the mean stops improving (docs/SURROGATE_ARMS.md, "An ensemble of trained models").
pub const MAX_MEMBERS: usize = 16;

#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
struct EnsembleFile {
    members: Vec<PathBuf>,
}

/// Loads `dir/ensemble.toml` and its members. The members must be run folders with the same
/// network (`[model]`) and byte-identical `tensors.json`, since their outputs are averaged in
/// the normalized space those statistics define; anything else is an error naming the file.
pub fn load_ensemble(dir: &Path, device: &Device) -> Result<TrainedModel> {
    let path = dir.join(ENSEMBLE_FILE);
    let text = files::read_to_string(&path, files::limits::TEXT, "ensemble file")?;
    let file: EnsembleFile = toml::from_str(&text).map_err(|e| file_error(&path, e))?;
    if file.members.len() < 2 {
        return Err(file_error(
            &path,
            format!(
                "members: {} run folder(s); an ensemble averages at least 2",
                file.members.len()
            ),
        ));
    }
    if file.members.len() > MAX_MEMBERS {
        return Err(file_error(
            &path,
            format!(
                "members: {} run folders; at most {MAX_MEMBERS} (each is a network call per frame)",
                file.members.len()
            ),
        ));
    }
    // The same run twice would weigh one network double, whatever its spelling.
    let resolved: Vec<PathBuf> = file
        .members
        .iter()
        .map(|m| dir.join(m).canonicalize().unwrap_or_else(|_| dir.join(m)))
        .collect();
    for (k, run) in resolved.iter().enumerate() {
        if let Some(first) = resolved[..k].iter().position(|r| r == run) {
            return Err(file_error(
                &path,
                format!(
                    "members {} and {} are the same run folder ({})",
                    first + 1,
                    k + 1,
                    run.display()
                ),
            ));
        }
    }
    let (mut head, head_tensors) = load_member(dir, &path, &file.members[0], device)?;
    let mut members = Vec::new();
    let mut networks = vec![head.run.clone()];
    for member in &file.members[1..] {
        let (trained, tensors) = load_member(dir, &path, member, device)?;
        let run = &trained.run;
        if trained.config.model != head.config.model {
            let difference = trained
                .config
                .first_difference(&head.config)
                .unwrap_or_default();
            return Err(file_error(
                &run.join("config.toml"),
                format!(
                    "another network than the first member's ({difference}): an ensemble \
                     averages networks of one configuration"
                ),
            ));
        }
        if tensors != head_tensors {
            return Err(file_error(
                &run.join(super::TENSORS_MANIFEST),
                format!(
                    "differs from {}'s: an ensemble's members must be trained on the same \
                     tensors",
                    head.run.display()
                ),
            ));
        }
        networks.push(run.clone());
        members.push(trained.model);
    }
    head.run = dir.to_path_buf();
    head.members = members;
    head.networks = networks;
    Ok(head)
}

/// One member of the ensemble file `path`: a run folder (relative to `dir`) and the text of
/// its `tensors.json`, which the members must share byte for byte.
fn load_member(
    dir: &Path,
    path: &Path,
    member: &Path,
    device: &Device,
) -> Result<(TrainedModel, String)> {
    let run = dir.join(member);
    if !run.is_dir() || run.join(ENSEMBLE_FILE).exists() {
        return Err(file_error(
            path,
            format!("member {}: not a run folder", run.display()),
        ));
    }
    let trained = TrainedModel::load_run_folder(&run, device)?;
    let manifest = run.join(super::TENSORS_MANIFEST);
    let tensors = files::read_to_string(&manifest, files::limits::TEXT, "tensors manifest")?;
    Ok((trained, tensors))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_shipped_model_is_the_single_network_and_one_more() {
        let device = Device::flex();
        let pair = TrainedModel::load_named("builtin", &device).unwrap();
        let single = TrainedModel::load_named("builtin-single", &device).unwrap();
        assert_eq!(pair.members.len(), 1);
        assert_eq!(pair.networks.len(), 2);
        assert_eq!(
            pair.networks[0].canonicalize().unwrap(),
            super::super::builtin_single_dir().canonicalize().unwrap()
        );
        assert_eq!(pair.config.model, single.config.model);
        assert_eq!(pair.run, super::super::builtin_dir());
        assert!(single.members.is_empty());
    }
}
