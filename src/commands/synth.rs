//! `dit-garment synth`: a dataset from a TOML spec, sequences in parallel, resumable, sharded
//! by Slurm job arrays or Kubernetes indexed jobs.
//!
//! The dataset folder's layout is in `crate::dataset_dir`. Every file is written to a
//! temporary name and renamed, so a killed run leaves only whole files; a re-run skips
//! sequences whose record exists and whose recording matches the record's checksum. Each
//! sequence is a scene configuration built from the spec's per-sequence keys (the same key
//! names, docs/DATASETS.md), recorded in the sequence's metadata.

use std::collections::HashMap;
use std::io::Write;
use std::sync::Arc;
use std::sync::atomic::{AtomicUsize, Ordering};
use std::time::{Duration, Instant};

use anyhow::{Context, Result, bail};
use indicatif::{ProgressBar, ProgressDrawTarget, ProgressStyle};
use motions::BodyModel;
use rayon::prelude::*;
use serde_json::json;
use sim::dataset::{
    Attempt, DatasetDir, DatasetSpec, GateResult, ManifestRecord, PlannedSequence, expand_motions,
    finished_record, plan,
};
use sim::scene::BodyAttachment;
use sim::{SceneConfig, SolverParams};

use crate::cli::SynthArgs;
use crate::inputs;
use crate::output::{write_atomic, write_json};
use crate::run::{RecordOptions, is_deadline, prepare_with, record};

/// The tiny example spec (4 sequences of 30 frames).
pub const TINY_SPEC: &str = include_str!("../../specs/tiny.toml");
/// The paper-like example spec on the built-in library.
pub const PAPER_SPEC: &str = include_str!("../../specs/paper.toml");

/// This task's shard (K, N): `--shard K/N`, else a Slurm job array, else a Kubernetes indexed
/// job (with `--shard-count`), else the whole dataset.
fn shard(args: &SynthArgs) -> Result<(usize, usize)> {
    let env = |name: &str| -> Result<Option<usize>> {
        match std::env::var(name) {
            Ok(v) => Ok(Some(v.trim().parse().with_context(|| {
                format!("environment variable {name}='{v}' is not a number")
            })?)),
            Err(_) => Ok(None),
        }
    };
    let (k, n) = if let Some(s) = &args.shard {
        let (k, n) = s
            .split_once('/')
            .with_context(|| format!("--shard '{s}' must be K/N, e.g. 0/4"))?;
        let parse = |v: &str| {
            v.trim()
                .parse::<usize>()
                .with_context(|| format!("--shard '{s}' must be K/N with whole numbers"))
        };
        (parse(k)?, parse(n)?)
    } else if let Some(id) = env("SLURM_ARRAY_TASK_ID")? {
        let count = env("SLURM_ARRAY_TASK_COUNT")?
            .context("SLURM_ARRAY_TASK_ID is set but SLURM_ARRAY_TASK_COUNT is not")?;
        let min = env("SLURM_ARRAY_TASK_MIN")?.unwrap_or(0);
        (
            id.checked_sub(min)
                .context("SLURM_ARRAY_TASK_ID < SLURM_ARRAY_TASK_MIN")?,
            count,
        )
    } else if let Some(index) = env("JOB_COMPLETION_INDEX")? {
        let count = args
            .shard_count
            .context("JOB_COMPLETION_INDEX is set: pass the job's completions as --shard-count")?;
        (index, count)
    } else {
        (0, 1)
    };
    if n == 0 || k >= n {
        bail!("shard {k}/{n} is out of range (K must be below N)");
    }
    Ok((k, n))
}

/// Removes what killed runs left: temporary files of this shard's sequences.
fn remove_leftovers(dir: &DatasetDir, ids: &[&str]) -> Result<usize> {
    let mut removed = 0;
    for folder in ["sequences", "records"] {
        let path = dir.root.join(folder);
        let Ok(entries) = std::fs::read_dir(&path) else {
            continue;
        };
        for entry in entries.flatten() {
            let name = entry.file_name().to_string_lossy().into_owned();
            if name.ends_with(".tmp")
                && ids.iter().any(|id| {
                    name.starts_with(&format!("{id}.mcap."))
                        || name.starts_with(&format!("{id}.json."))
                })
            {
                std::fs::remove_file(entry.path())?;
                removed += 1;
            }
        }
    }
    Ok(removed)
}

/// What every sequence of a run shares.
struct RunContext<'a> {
    spec: &'a DatasetSpec,
    dir: &'a DatasetDir,
    model: Arc<BodyModel>,
    /// The `--model` file, recorded in every sequence's configuration.
    model_file: Option<String>,
    templates: HashMap<String, (Arc<garments::Garment>, Vec<BodyAttachment>)>,
    software: String,
}

/// Simulates one sequence (with retries) into its recording and record.
fn synthesize(ctx: &RunContext, p: &PlannedSequence) -> Result<ManifestRecord> {
    let spec = ctx.spec;
    let (garment, attachments) = &ctx.templates[&p.garment];
    let file = DatasetDir::sequence_file(&p.id);
    let path = ctx.dir.root.join(&file);
    let settings = std::iter::once((spec.solver.substeps, spec.solver.max_iterations)).chain(
        std::iter::repeat_n(
            (spec.gates.retry_substeps, spec.gates.retry_iterations),
            spec.gates.retries,
        ),
    );
    let mut attempts = Vec::new();
    let mut frames = 0;
    let started = Instant::now();
    for (substeps, iterations) in settings {
        // The recording always belongs to the last attempt that finished.
        let _ = std::fs::remove_file(&path);
        let config = SceneConfig {
            garment: p.garment.clone(),
            motion: p.motion.clone(),
            model: ctx.model_file.clone(),
            betas: p.betas.clone(),
            friction: p.friction,
            frames: spec.sequence.frames,
            blend_frames: spec.sequence.blend_frames,
            settle_frames: spec.sequence.settle_frames,
            seed: Some(p.seed),
            material: p.material,
            solver: SolverParams {
                substeps,
                max_iterations: iterations,
                self_contact: spec.solver.self_contact,
                self_contact_distance: spec.solver.self_contact_distance,
                self_friction: spec.solver.self_friction,
                acceleration: spec.solver.acceleration,
                ..SolverParams::default()
            },
            record: sim::config::RecordConfig::default(),
        };
        let solver = config.solver;
        let attempt_started = Instant::now();
        let prepared = prepare_with(
            ctx.model.clone(),
            garment.clone(),
            attachments.clone(),
            config,
        );
        let gates = match prepared {
            Err(e) => GateResult::unfinished(format!("could not set up: {e:#}"), false),
            Ok(prepared) => {
                frames = prepared.scene.num_frames();
                let options = RecordOptions {
                    quiet: true,
                    deadline: Some(attempt_started + Duration::from_secs_f64(spec.gates.timeout_s)),
                    ..RecordOptions::default()
                };
                match record(&prepared, &path, options) {
                    Ok(summary) => GateResult::judge(&summary, &spec.gates),
                    Err(e) if is_deadline(&e) => GateResult::unfinished(
                        format!("time-out after {} s", spec.gates.timeout_s),
                        true,
                    ),
                    Err(e) => GateResult::unfinished(format!("solver: {e:#}"), false),
                }
            }
        };
        let passed = gates.passed;
        attempts.push(Attempt {
            solver,
            gates,
            wall_s: attempt_started.elapsed().as_secs_f64(),
        });
        if passed {
            break;
        }
    }
    let last = attempts.last().expect("at least one attempt");
    let ok = last.gates.passed;
    let (file, sha256, bytes) = if path.exists() {
        let (sha, bytes) = files::sha256_file(&path)?;
        (Some(file), Some(sha), bytes)
    } else {
        (None, None, 0)
    };
    Ok(ManifestRecord {
        id: p.id.clone(),
        split: p.split.clone(),
        garment: p.garment.clone(),
        motion: p.motion.clone(),
        betas: p.betas.clone(),
        material: p.material,
        friction: p.friction,
        seed: p.seed,
        frames,
        vertices: garment.positions.len(),
        status: if ok { "ok" } else { "failed" }.into(),
        reason: (!ok).then(|| last.gates.failed.join("; ")),
        attempts,
        file,
        sha256,
        bytes,
        software: ctx.software.clone(),
        wall_s: started.elapsed().as_secs_f64(),
    })
}

/// Refuses a folder that holds another spec's dataset.
fn check_spec(dir: &DatasetDir, spec: &DatasetSpec) -> Result<()> {
    let path = dir.spec();
    if path.exists() && &DatasetSpec::load(&path)? != spec {
        bail!(
            "{} holds a dataset of a different spec (its spec.toml differs); use another --out",
            dir.root.display()
        );
    }
    Ok(())
}

/// Stores the spec in the folder (checked by [`check_spec`] first).
fn store_spec(dir: &DatasetDir, spec: &DatasetSpec) -> Result<()> {
    let path = dir.spec();
    if path.exists() {
        return Ok(());
    }
    write_atomic(&path, |w| {
        w.write_all(spec.to_toml().as_bytes())?;
        Ok(())
    })
}

/// Writes the manifest when every planned sequence has a record (from `known`, this run's,
/// else from the folder); returns the missing count.
fn write_manifest(
    dir: &DatasetDir,
    planned: &[PlannedSequence],
    known: &HashMap<String, ManifestRecord>,
) -> Result<usize> {
    let mut records = Vec::with_capacity(planned.len());
    let mut missing = 0;
    for p in planned {
        match known
            .get(&p.id)
            .cloned()
            .or_else(|| finished_record(dir, &p.id))
        {
            Some(r) => records.push(r),
            None => missing += 1,
        }
    }
    if missing == 0 {
        files::write_json_lines(&dir.manifest(), &records)?;
    }
    Ok(missing)
}

pub fn run(args: &SynthArgs) -> Result<()> {
    let max = crate::run::MAX_THREADS;
    if let Some(jobs) = args.jobs.filter(|&j| j > max) {
        bail!("--jobs {jobs}: at most {max}");
    }
    if let Some(which) = &args.example_spec {
        print!(
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
    let spec = DatasetSpec::load(spec_path)?;
    let (k, n) = shard(args)?;
    let motions = expand_motions(&spec).with_context(|| format!("{}", spec_path.display()))?;
    let planned = plan(&spec, &motions).with_context(|| format!("{}", spec_path.display()))?;
    let dir = DatasetDir::new(out);
    // Everything the spec names is checked before the folder is touched, so a refused spec
    // (a typo in a motion or garment, another spec's folder) leaves the folder as it was.
    check_spec(&dir, &spec)?;
    let model = Arc::new(inputs::body_model(args.model.body_model.as_deref())?);
    let neutral = model.shape(&[])?;
    for (source, _) in &motions {
        inputs::motion(source, &model, &neutral)
            .with_context(|| format!("{}: motion '{source}'", spec_path.display()))?;
    }
    let mine: Vec<&PlannedSequence> = planned
        .iter()
        .enumerate()
        .filter(|(i, _)| i % n == k)
        .map(|(_, p)| p)
        .collect();
    // The templates of this shard's garments, made (or read from the cache) in parallel.
    let mut names: Vec<&String> = mine.iter().map(|p| &p.garment).collect();
    names.sort();
    names.dedup();
    let made = names
        .par_iter()
        .map(|name| {
            let (garment, attachments) = inputs::garment(name, &model)
                .with_context(|| format!("{}: garment '{name}'", spec_path.display()))?;
            Ok(((*name).clone(), (Arc::new(garment), attachments)))
        })
        .collect::<Result<Vec<_>>>()?;
    std::fs::create_dir_all(&dir.root)
        .with_context(|| format!("cannot create {}", dir.root.display()))?;
    store_spec(&dir, &spec)?;
    files::write_json_lines(&dir.plan(), &planned)?;
    let ids: Vec<&str> = mine.iter().map(|p| p.id.as_str()).collect();
    let leftovers = remove_leftovers(&dir, &ids)?;
    // Finished sequences (checked against their checksums once) and the rest.
    let mut known = HashMap::new();
    let mut todo: Vec<&PlannedSequence> = Vec::new();
    for p in &mine {
        match finished_record(&dir, &p.id) {
            Some(r) => {
                known.insert(p.id.clone(), r);
            }
            None => todo.push(p),
        }
    }
    println!(
        "synth '{}': {} sequences planned, shard {k}/{n} has {}, {} already done{}",
        spec.name,
        planned.len(),
        mine.len(),
        mine.len() - todo.len(),
        if leftovers > 0 {
            format!(", {leftovers} leftover temporary files removed")
        } else {
            String::new()
        }
    );
    for (name, (garment, _)) in &made {
        let template_path = dir.template(name);
        if !template_path.exists() {
            sim::templates::write_template(&template_path, garment)?;
        }
    }
    let templates: HashMap<_, _> = made.into_iter().collect();
    let ctx = RunContext {
        spec: &spec,
        dir: &dir,
        model,
        model_file: args
            .model
            .body_model
            .as_ref()
            .map(|m| m.display().to_string()),
        templates,
        software: format!("dit-garment {}", env!("CARGO_PKG_VERSION")),
    };
    let jobs = args
        .jobs
        .unwrap_or_else(|| std::thread::available_parallelism().map_or(1, |n| n.get()));
    let pool = rayon::ThreadPoolBuilder::new()
        .num_threads(jobs.max(1))
        .build()?;
    let bar = ProgressBar::new(todo.len() as u64).with_style(
        ProgressStyle::with_template("synth [{bar:30}] {pos}/{len} sequences ({msg}, eta {eta})")?
            .progress_chars("=> "),
    );
    if args.quiet {
        bar.set_draw_target(ProgressDrawTarget::hidden());
    }
    let started = Instant::now();
    let frames_done = AtomicUsize::new(0);
    let failed = AtomicUsize::new(0);
    let made = pool.install(|| {
        todo.par_iter()
            .map(|p| -> Result<ManifestRecord> {
                let record = synthesize(&ctx, p).with_context(|| format!("sequence {}", p.id))?;
                write_json(&dir.record(&p.id), &record)?;
                let done = frames_done.fetch_add(record.frames, Ordering::Relaxed) + record.frames;
                if !record.ok() {
                    failed.fetch_add(1, Ordering::Relaxed);
                }
                // One line per sequence where no bar is drawn (logs of batch jobs), and for every
                // failure.
                if !record.ok() || (bar.is_hidden() && !args.quiet) {
                    let line = format!(
                        "  {} {} ({} frames, {:.1} s){}",
                        record.id,
                        record.status,
                        record.frames,
                        record.wall_s,
                        record
                            .reason
                            .as_ref()
                            .map(|r| format!(": {r}"))
                            .unwrap_or_default()
                    );
                    bar.suspend(|| eprintln!("{line}"));
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
    known.extend(made.into_iter().map(|r| (r.id.clone(), r)));
    bar.finish_and_clear();
    let wall = started.elapsed().as_secs_f64();
    let frames = frames_done.load(Ordering::Relaxed);
    let failed = failed.load(Ordering::Relaxed);
    let missing = write_manifest(&dir, &planned, &known)?;
    let summary = json!({
        "name": spec.name, "shard": [k, n], "planned": planned.len(), "shard_sequences": mine.len(),
        "simulated": todo.len(), "skipped": mine.len() - todo.len(), "failed": failed,
        "frames": frames, "wall_s": wall,
        "frames_per_s": if wall > 0.0 { frames as f64 / wall } else { 0.0 },
        "sequences_per_hour": if wall > 0.0 { todo.len() as f64 / wall * 3600.0 } else { 0.0 },
        "jobs": jobs, "manifest": (missing == 0).then(|| dir.manifest()),
    });
    println!(
        "synth: {} sequences simulated ({failed} failed their gates), {frames} frames in {wall:.1} s ({:.1} frames/s, {:.0} sequences/h, {jobs} jobs)",
        todo.len(),
        summary["frames_per_s"].as_f64().unwrap_or(0.0),
        summary["sequences_per_hour"].as_f64().unwrap_or(0.0),
    );
    if missing == 0 {
        println!("  wrote {}", dir.manifest().display());
    } else {
        println!(
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
