//! `dit-garment synth`: a dataset from a TOML spec, sequences in parallel, resumable, sharded
//! by Slurm job arrays or Kubernetes indexed jobs.
//!
//! One sequence's run (retries, gates), the folder's layout and its checks are
//! `dataset`'s; this command picks the shard's sequences, runs them in parallel with a
//! progress bar and prints. Every file is written to a temporary name and renamed, so a killed
//! run leaves only whole files; a re-run skips sequences whose record exists and whose
//! recording matches the record's checksum.

use std::collections::HashMap;
use std::path::Path;
use std::sync::Arc;
use std::sync::atomic::{AtomicUsize, Ordering};
use std::time::Instant;

use anyhow::{Context, Result, bail};
use dataset::{
    DatasetDir, DatasetSpec, ManifestRecord, PlannedSequence, Shard, Synthesis, Template,
    expand_motions, make_templates, plan, split_finished,
};
use motions::BodyModel;
use rayon::prelude::*;
use serde_json::json;

use crate::cli::SynthArgs;
use crate::run::progress;
use files::write_json;

/// The tiny example spec (4 sequences of 30 frames).
pub const TINY_SPEC: &str = include_str!("../../specs/tiny.toml");
/// The paper-like example spec on the built-in library.
pub const PAPER_SPEC: &str = include_str!("../../specs/paper.toml");

pub fn run(args: &SynthArgs) -> Result<()> {
    let max = crate::run::MAX_THREADS;
    if let Some(jobs) = args.jobs.filter(|&j| j > max) {
        bail!("--jobs {jobs}: at most {max}");
    }
    if let Some(which) = &args.example_spec {
        say_part!(
            "{}",
            if which == "paper" {
                PAPER_SPEC
            } else {
                TINY_SPEC
            }
        );
        return Ok(());
    }
    let (Some(spec_path), Some(out)) = (&args.spec, &args.out) else {
        bail!("synth needs --spec FILE and --out DIR (or --example-spec tiny|paper)");
    };
    let mut job = prepare(args, spec_path, out)?;
    let (mut known, todo) = open_folder(&job)?;
    let synthesis = Synthesis {
        templates: std::mem::take(&mut job.templates),
        unusable: std::mem::take(&mut job.unusable),
        spec: &job.spec,
        dir: &job.dir,
        model: job.model.clone(),
        model_file: args
            .model
            .body_model
            .as_ref()
            .map(|m| m.display().to_string()),
        software: format!("dit-garment {}", env!("CARGO_PKG_VERSION")),
    };
    let jobs = args
        .jobs
        .unwrap_or_else(|| std::thread::available_parallelism().map_or(1, |n| n.get()));
    let mut outcome = simulate(&synthesis, &todo, jobs, args.quiet)?;
    known.extend(
        std::mem::take(&mut outcome.records)
            .into_iter()
            .map(|r| (r.sequence.id.clone(), r)),
    );
    let missing = job.dir.write_manifest(&job.planned, &known)?;
    report(args, &job, &todo, &outcome, jobs, missing)
}

/// What a run of `synth` works from, all checked before the folder is touched.
struct Job {
    spec: DatasetSpec,
    dir: DatasetDir,
    shard: Shard,
    planned: Vec<PlannedSequence>,
    /// This shard's part of `planned`.
    mine: Vec<PlannedSequence>,
    model: Arc<BodyModel>,
    /// The templates of this shard's garments, by name.
    templates: HashMap<String, Template>,
    /// Garments whose template failed its gates, with why.
    unusable: HashMap<String, String>,
}

/// The spec read and planned, every motion it names loaded and this shard's templates made (or
/// read from the cache), so a refused spec (a typo in a motion or garment, another spec's
/// folder) leaves the folder as it was. A template that fails its gates makes its sequences
/// fail; any other problem with a garment stops the run here.
fn prepare(args: &SynthArgs, spec_path: &Path, out: &Path) -> Result<Job> {
    let spec = DatasetSpec::load(spec_path)?;
    let shard = Shard::resolve(args.shard.as_deref(), args.shard_count, |name| {
        std::env::var(name).ok()
    })?;
    let motions = expand_motions(&spec).with_context(|| format!("{}", spec_path.display()))?;
    let planned = plan(&spec, &motions).with_context(|| format!("{}", spec_path.display()))?;
    let dir = DatasetDir::new(out);
    dir.check_spec(&spec)?;
    let model = Arc::new(sim::sources::body_model(args.model.body_model.as_deref())?);
    let neutral = model.shape(&[])?;
    for (source, _) in &motions {
        sim::sources::motion(source, &model, &neutral)
            .with_context(|| format!("{}: motion '{source}'", spec_path.display()))?;
    }
    let mine: Vec<PlannedSequence> = shard.take(&planned).into_iter().cloned().collect();
    let cache = sim::templates::cache_dir();
    let making = |name: &str, path: &Path| crate::inputs::making_template(name)(path);
    let (templates, unusable) =
        make_templates(&mine.iter().collect::<Vec<_>>(), &model, &cache, &making)
            .with_context(|| spec_path.display().to_string())?;
    for why in unusable.values() {
        eprintln!("  {why}: its sequences are recorded as failed");
    }
    Ok(Job {
        spec,
        dir,
        shard,
        planned,
        mine,
        model,
        templates,
        unusable,
    })
}

/// The folder created (spec, plan, templates; leftover temporary files removed): the records
/// already finished, and the sequences left to simulate.
fn open_folder(job: &Job) -> Result<(HashMap<String, ManifestRecord>, Vec<PlannedSequence>)> {
    let dir = &job.dir;
    std::fs::create_dir_all(&dir.root)
        .with_context(|| format!("cannot create {}", dir.root.display()))?;
    dir.store_spec(&job.spec)?;
    files::write_json_lines(&dir.plan(), &job.planned)?;
    let ids: Vec<&str> = job.mine.iter().map(|p| p.id.as_str()).collect();
    let leftovers = dir.remove_leftovers(&ids)?;
    let (known, todo) = split_finished(dir, &job.mine.iter().collect::<Vec<_>>());
    say!(
        "synth '{}': {} sequences planned, shard {}/{} has {}, {} already done{}",
        job.spec.name,
        job.planned.len(),
        job.shard.index,
        job.shard.count,
        job.mine.len(),
        job.mine.len() - todo.len(),
        if leftovers > 0 {
            format!(", {leftovers} leftover temporary files removed")
        } else {
            String::new()
        }
    );
    for (name, (garment, _)) in &job.templates {
        let template_path = dir.template(name);
        if !template_path.exists() {
            sim::templates::write_template(&template_path, garment)?;
        }
    }
    Ok((known, todo.into_iter().cloned().collect()))
}

/// What the simulation stage did.
struct Outcome {
    records: Vec<ManifestRecord>,
    frames: usize,
    failed: usize,
    wall_s: f64,
}

/// The sequences of `todo` simulated on `jobs` threads, each record written as it finishes,
/// with a progress bar (and a line per sequence where no bar is drawn, and for every failure).
fn simulate(
    synthesis: &Synthesis,
    todo: &[PlannedSequence],
    jobs: usize,
    quiet: bool,
) -> Result<Outcome> {
    let pool = rayon::ThreadPoolBuilder::new()
        .num_threads(jobs.max(1))
        .build()?;
    let bar = progress(
        "synth",
        todo.len(),
        "sequences",
        "({msg}, eta {eta})",
        quiet,
    );
    let started = Instant::now();
    let frames_done = AtomicUsize::new(0);
    let failed = AtomicUsize::new(0);
    let records = pool.install(|| {
        todo.par_iter()
            .map(|p| -> Result<ManifestRecord> {
                let record = synthesis
                    .sequence(p)
                    .with_context(|| format!("sequence {}", p.id))?;
                write_json(&synthesis.dir.record(&p.id), &record)?;
                let done = frames_done.fetch_add(record.frames, Ordering::Relaxed) + record.frames;
                if !record.ok() {
                    failed.fetch_add(1, Ordering::Relaxed);
                }
                if !record.ok() || (bar.is_hidden() && !quiet) {
                    bar.suspend(|| eprintln!("  {record}"));
                }
                bar.set_message(format!(
                    "{:.1} frames/s",
                    done as f64 / started.elapsed().as_secs_f64()
                ));
                bar.inc(1);
                Ok(record)
            })
            .collect::<Result<Vec<_>>>()
    })?;
    bar.finish_and_clear();
    Ok(Outcome {
        records,
        frames: frames_done.load(Ordering::Relaxed),
        failed: failed.load(Ordering::Relaxed),
        wall_s: started.elapsed().as_secs_f64(),
    })
}

/// The summary printed (and written as JSON with `--json`); `missing` counts sequences of
/// other shards not done yet.
fn report(
    args: &SynthArgs,
    job: &Job,
    todo: &[PlannedSequence],
    outcome: &Outcome,
    jobs: usize,
    missing: usize,
) -> Result<()> {
    let (dir, wall, frames, failed) = (&job.dir, outcome.wall_s, outcome.frames, outcome.failed);
    let per_s = |count: usize| if wall > 0.0 { count as f64 / wall } else { 0.0 };
    let (frames_per_s, per_hour, simulated) =
        (per_s(frames), per_s(todo.len()) * 3600.0, todo.len());
    let summary = json!({
        "name": job.spec.name, "shard": [job.shard.index, job.shard.count],
        "planned": job.planned.len(), "shard_sequences": job.mine.len(),
        "simulated": simulated, "skipped": job.mine.len() - simulated, "failed": failed,
        "frames": frames, "wall_s": wall, "frames_per_s": frames_per_s,
        "sequences_per_hour": per_hour, "jobs": jobs,
        "manifest": (missing == 0).then(|| dir.manifest()),
    });
    say!(
        "synth: {simulated} sequences simulated ({failed} failed their gates), {frames} frames in {wall:.1} s ({frames_per_s:.1} frames/s, {per_hour:.0} sequences/h, {jobs} jobs)",
    );
    if missing == 0 {
        say!("  wrote {}", dir.manifest().display());
    } else {
        say!(
            "  {missing} sequences of other shards are not done yet; when all shards finish, run `dit-garment dataset merge {} {}`",
            dir.root.display(),
            dir.root.display()
        );
    }
    if let Some(path) = &args.json {
        write_json(path, &summary)?;
    }
    Ok(())
}
