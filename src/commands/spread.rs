//! `dit-garment dataset spread`: the ground truth's own spread. Each finished sequence is
//! simulated again from the configuration its recording carries, nudged a little (1% stiffer
//! cloth, one more substep or solver iteration), and the rerun is scored against the
//! recording as a prediction would be (evaluate's protocol: motion frames, every 5th). No
//! deterministic predictor from a short pose window can come closer to the truth than the
//! truth comes to itself, so this is the floor of dynamics beside `floor`, the floor of the
//! UV maps (docs/SURROGATE.md).

use std::collections::BTreeMap;
use std::path::Path;
use std::time::Instant;

use anyhow::{Context, Result, bail};
use dataset::{DatasetDir, ManifestRecord};
use rayon::prelude::*;
use serde_json::json;
use sim::SceneConfig;
use sim::recording::Recording;
use sim::run::Prepared;
use surrogate::data::Sequence;
use surrogate::evaluate::family::fill_families;
use surrogate::evaluate::tables::{
    SequenceResult, aggregate, aggregate_by, grouped_text_table, text_table,
};
use surrogate::evaluate::{Method, Truth};

use crate::run::progress;
use files::write_json;

/// How the rerun differs from the recorded run.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Perturbation {
    /// Nothing: the engine is deterministic, so the spread is zero but for the recording's
    /// f32 rounding (a check).
    None,
    /// Stretch stiffness k_s 1% higher.
    Stiffness,
    /// One more substep per frame.
    Substep,
    /// One more solver iteration per substep.
    Iteration,
}

impl Perturbation {
    /// Parses `none`, `k_s`, `substeps` or `iterations`.
    pub fn parse(name: &str) -> Result<Self> {
        Ok(match name {
            "none" => Self::None,
            "k_s" => Self::Stiffness,
            "substeps" => Self::Substep,
            "iterations" => Self::Iteration,
            other => bail!("--perturb {other}: none, k_s, substeps or iterations"),
        })
    }

    fn apply(self, config: &mut SceneConfig) {
        match self {
            Self::None => {}
            Self::Stiffness => config.material.stretch *= 1.01,
            Self::Substep => config.solver.substeps += 1,
            Self::Iteration => config.solver.max_iterations += 1,
        }
    }
}

/// One sequence simulated again under `perturbation` and scored against its recording.
fn rerun(
    dir: &Path,
    record: &ManifestRecord,
    perturbation: Perturbation,
) -> Result<SequenceResult> {
    let file = record.file.as_deref().context("no recording")?;
    let path = dir.join(file);
    let seq = Sequence::read(&path)?;
    let mut config = Recording::scene_config(&path)?;
    perturbation.apply(&mut config);
    let prepared = Prepared::load(config.validated()?, &sim::templates::cache_dir(), |_| {})?;
    let truth = Truth::new(&seq, &prepared.model, 0)?;
    let frames = truth.frames();
    let started = Instant::now();
    let mut garment = Vec::with_capacity(frames.len());
    prepared.scene.run(&prepared.model, |frame| {
        if frames.binary_search(&frame.index).is_ok() {
            garment.push(frame.garment.to_vec());
        }
        Ok(())
    })?;
    if garment.len() != frames.len() {
        bail!(
            "the rerun made {} of the {} motion frames the recording has",
            garment.len(),
            frames.len()
        );
    }
    let fps = frames.len() as f64 / started.elapsed().as_secs_f64().max(1e-9);
    Ok(SequenceResult {
        id: record.sequence.id.clone(),
        split: record.sequence.split.to_string(),
        garment: record.sequence.garment.clone(),
        family: String::new(),
        motion: record.sequence.motion.clone(),
        file: file.to_string(),
        settings: json!({"perturb": format!("{perturbation:?}")}),
        methods: BTreeMap::from([(Method::Resimulated, truth.score(&garment, fps))]),
        simulation: truth.simulation(),
    })
}

/// `dataset spread DIR`: every finished sequence of `splits` (all where empty), at most
/// `max_sequences` of them, simulated again and scored; tables per split, family and motion.
pub fn spread(
    dir: &Path,
    splits: &[String],
    perturbation: Perturbation,
    max_sequences: Option<usize>,
    json_path: Option<&Path>,
    quiet: bool,
) -> Result<()> {
    let records: Vec<ManifestRecord> =
        files::read_json_lines(&DatasetDir::new(dir).manifest(), "dataset manifest")?;
    let chosen: Vec<&ManifestRecord> = records
        .iter()
        .filter(|r| {
            r.ok() && (splits.is_empty() || splits.iter().any(|s| s == r.sequence.split.name()))
        })
        .take(max_sequences.unwrap_or(usize::MAX))
        .collect();
    if chosen.is_empty() {
        bail!(
            "{}: no finished sequences in the splits asked for",
            dir.display()
        );
    }
    let bar = progress(
        "spread",
        chosen.len(),
        "sequences",
        "(eta {eta}) {msg}",
        quiet,
    );
    let mut results = chosen
        .par_iter()
        .map(|r| {
            let result = rerun(dir, r, perturbation)
                .with_context(|| format!("{}: sequence {}", dir.display(), r.sequence.id));
            bar.inc(1);
            result
        })
        .collect::<Result<Vec<_>>>()?;
    bar.finish_and_clear();
    // Families from the templates as worn on the default body (a body model of the user's
    // shifts a template's distances from the body by millimetres, not its family).
    fill_families(&mut results, dir, &sim::sources::body_model(None)?)?;
    let (splits_rows, _) = aggregate(&results);
    let families = aggregate_by(&results, |r| r.family.clone());
    let motions = aggregate_by(&results, |r| r.motion.clone());
    if let Some(path) = json_path {
        write_json(
            path,
            &json!({"perturb": format!("{perturbation:?}"), "splits": splits_rows,
                    "families": families, "motions": motions, "sequences": results,
                    "units": surrogate::evaluate::units()}),
        )?;
    }
    say!(
        "spread: {} sequences simulated again ({perturbation:?}) and scored against their recordings",
        results.len()
    );
    say_part!("{}", text_table(&splits_rows));
    for (label, groups) in [("family", families), ("motion", motions)] {
        if groups.values().any(|g| g.len() > 1) {
            say_part!("\n{}", grouped_text_table(label, &groups));
        }
    }
    Ok(())
}
