//! `dit-garment dataset verify | stats | merge | tensors` (`spread` in `spread.rs`): checking, summarizing and merging dataset
//! folders written by `synth` (layout in `synth.rs` and docs/DATASETS.md).

use std::path::{Path, PathBuf};

use anyhow::{Context, Result, bail};
use dataset::{DatasetDir, ManifestRecord, Split, load, stats};
use surrogate::data::{ConditionScaling, TensorOptions, write_tensors};
use surrogate::geometry::TargetKind;

use crate::cli::DatasetCommand;
use crate::run::progress;
use files::write_json;

pub fn run(command: DatasetCommand) -> Result<()> {
    match command {
        DatasetCommand::Verify { dir, json } => verify(&dir, json.as_deref()),
        DatasetCommand::Stats { dir, json } => stats_cmd(&dir, json.as_deref()),
        DatasetCommand::Merge { out, dirs } => merge(&out, &dirs),
        DatasetCommand::Spread {
            dir,
            splits,
            perturb,
            max_sequences,
            json,
            quiet,
        } => crate::commands::spread::spread(
            &dir,
            &splits,
            crate::commands::spread::Perturbation::parse(&perturb)?,
            max_sequences,
            json.as_deref(),
            quiet,
        ),
        DatasetCommand::Tensors {
            dirs,
            out,
            resolution,
            target,
            conditions,
            body_nearest,
            window,
            every,
            shard_frames,
            train_splits,
            mirror,
            mirror_max_gap_cm,
            model,
            quiet,
        } => {
            // Checked before any recording is read: each earlier frame adds 135 condition
            // values, and a shard must stay under the size a tensor file is read at.
            anyhow::ensure!(
                window <= 64,
                "--window {window}: at most 64 earlier frames (each adds 135 condition values)"
            );
            anyhow::ensure!(
                (1..=16384).contains(&shard_frames),
                "--shard-frames {shard_frames}: 1 to 16384 (a shard must stay under the 8 GiB a \
                 tensor file is read at)"
            );
            anyhow::ensure!(
                (0.0..=100.0).contains(&mirror_max_gap_cm),
                "--mirror-max-gap-cm {mirror_max_gap_cm}: 0 to 100 (cm)"
            );
            anyhow::ensure!(
                matches!(resolution, 32 | 64 | 128),
                "--resolution {resolution}: 32, 64 or 128"
            );
            let options = TensorOptions {
                resolution,
                target: TargetKind::parse(&target).context("unknown --target")?,
                window,
                every,
                shard_frames,
                conditions: ConditionScaling::parse(&conditions).context("unknown --conditions")?,
                nearest: body_nearest,
                train_splits: joined_splits(&train_splits)?,
                mirror,
                mirror_max_gap_m: mirror_max_gap_cm / 100.0,
                ..TensorOptions::default()
            };
            tensors(&dirs, &out, model.body_model.as_deref(), &options, quiet)
        }
    }
}

/// `--train-splits`: the held-out splits named, as flags indexed like [`Split::ALL`].
fn joined_splits(names: &[String]) -> Result<[bool; Split::ALL.len()]> {
    let mut joined = Vec::new();
    for name in names {
        let split = Split::parse(name).with_context(|| {
            format!(
                "--train-splits: unknown split {name:?} (splits: {})",
                Split::names()
            )
        })?;
        anyhow::ensure!(
            split != Split::Train,
            "--train-splits: name held-out splits only (train is always trained on)"
        );
        joined.push(split);
    }
    Ok(Split::ALL.map(|s| joined.contains(&s)))
}

/// `dataset tensors`: the surrogate's training tensors of one dataset or several combined.
fn tensors(
    dirs: &[PathBuf],
    out: &Path,
    model: Option<&Path>,
    options: &TensorOptions,
    quiet: bool,
) -> Result<()> {
    let model = sim::sources::body_model(model)?;
    let mut total = 0;
    for dir in dirs {
        let records: Vec<ManifestRecord> =
            files::read_json_lines(&DatasetDir::new(dir).manifest(), "dataset manifest")?;
        total += records.iter().filter(|r| r.ok()).count();
    }
    let bar = progress("tensors", total, "sequences", "(eta {eta})", quiet);
    let started = std::time::Instant::now();
    let names: Vec<String> = dirs.iter().map(|d| d.display().to_string()).collect();
    let manifest = write_tensors(dirs, out, &model, options, || bar.inc(1))
        .with_context(|| format!("making tensors of {}", names.join(", ")))?;
    bar.finish_and_clear();
    let frames: usize = manifest.splits.values().map(|s| s.frames).sum();
    say!(
        "tensors: {} sequences, {frames} frames of {} templates at {r} x {r} ({}, window {}, condition {} values) in {:.1} s",
        total,
        manifest.templates.len(),
        manifest.target.name(),
        manifest.window,
        manifest.condition_dim,
        started.elapsed().as_secs_f64(),
        r = manifest.resolution,
    );
    for (split, info) in &manifest.splits {
        let mirrored = match info.mirrored {
            0 => String::new(),
            n => format!(" ({n} of them also mirrored)"),
        };
        say!(
            "  {split}: {} frames of {} sequences{mirrored} in {} shards",
            info.frames,
            info.sequences,
            info.shards.len()
        );
    }
    if options.mirror {
        let lopsided: Vec<String> = manifest
            .templates
            .iter()
            .filter_map(|t| {
                let gap = t.mirror_gap_m?;
                (gap > options.mirror_max_gap_m && t.in_training())
                    .then(|| format!("{} ({:.2} cm)", t.name, 100.0 * gap))
            })
            .collect();
        if !lopsided.is_empty() {
            say!("  not mirrored (not symmetric): {}", lopsided.join(", "));
        }
    }
    say!("  wrote {}", out.join("manifest.json").display());
    Ok(())
}

fn verify(root: &Path, json: Option<&Path>) -> Result<()> {
    let found = dataset::verify(root)?;
    say!("verify {}: {found}", root.display());
    if let Some(path) = json {
        write_json(path, &found)?;
    }
    if let Some(first) = found.problems.first() {
        let count = found.problems.len();
        bail!(
            "{}: {count} problems found (first: {first})",
            root.display()
        );
    }
    say!("  every checksum, schema, count and gate result checks out");
    Ok(())
}

fn stats_cmd(root: &Path, json: Option<&Path>) -> Result<()> {
    let dir = DatasetDir::new(root);
    let (spec, _, records) = load(&dir)?;
    let s = stats(&records, sim::scene::FPS);
    say!(
        "dataset '{}' in {}: {} sequences ({} failed, {} retried), {} frames = {:.2} hours at 30 fps",
        spec.name,
        root.display(),
        s.sequences,
        s.failed,
        s.retried,
        s.frames,
        s.hours
    );
    say_part!("{s}");
    if let Some(path) = json {
        write_json(path, &s)?;
    }
    Ok(())
}

fn merge(out: &Path, roots: &[std::path::PathBuf]) -> Result<()> {
    let merged = dataset::merge(out, roots)?;
    say!(
        "merge: {merged} sequences from {} folders into {}",
        roots.len(),
        DatasetDir::new(out).manifest().display()
    );
    Ok(())
}
