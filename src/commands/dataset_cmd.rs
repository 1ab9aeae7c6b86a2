//! `dit-garment dataset verify | stats | merge`: checking, summarizing and merging dataset
//! folders written by `synth` (layout in `synth.rs` and docs/DATASETS.md).

use std::collections::{HashMap, HashSet};
use std::path::Path;

use anyhow::{Context, Result, bail};
use indicatif::{ProgressBar, ProgressDrawTarget, ProgressStyle};
use sim::dataset::{DatasetSpec, ManifestRecord, PlannedSequence, stats};
use sim::recording::Recording;
use surrogate::data::{ConditionScaling, TensorOptions, write_tensors};
use surrogate::geometry::TargetKind;

use crate::cli::DatasetCommand;
use crate::dataset_dir::{DatasetDir, finished_record};
use crate::output::write_json;

pub fn run(command: DatasetCommand) -> Result<()> {
    match command {
        DatasetCommand::Verify { dir, json } => verify(&dir, json.as_deref()),
        DatasetCommand::Stats { dir, json } => stats_cmd(&dir, json.as_deref()),
        DatasetCommand::Merge { out, dirs } => merge(&out, &dirs),
        DatasetCommand::Tensors {
            dir,
            out,
            resolution,
            target,
            conditions,
            window,
            every,
            shard_frames,
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
                ..TensorOptions::default()
            };
            tensors(&dir, &out, model.body_model.as_deref(), &options, quiet)
        }
    }
}

/// `dataset tensors`: the surrogate's training tensors of a dataset.
fn tensors(
    dir: &Path,
    out: &Path,
    model: Option<&Path>,
    options: &TensorOptions,
    quiet: bool,
) -> Result<()> {
    let model = crate::inputs::body_model(model)?;
    let records: Vec<ManifestRecord> =
        files::read_json_lines(&DatasetDir::new(dir).manifest(), "dataset manifest")?;
    let total = records.iter().filter(|r| r.ok()).count();
    let bar = ProgressBar::new(total as u64).with_style(
        ProgressStyle::with_template("tensors [{bar:30}] {pos}/{len} sequences (eta {eta})")?
            .progress_chars("=> "),
    );
    if quiet {
        bar.set_draw_target(ProgressDrawTarget::hidden());
    }
    let started = std::time::Instant::now();
    let manifest = write_tensors(dir, out, &model, options, || bar.inc(1))
        .with_context(|| format!("making tensors of {}", dir.display()))?;
    bar.finish_and_clear();
    let frames: usize = manifest.splits.values().map(|s| s.frames).sum();
    println!(
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
        println!(
            "  {split}: {} frames of {} sequences in {} shards",
            info.frames,
            info.sequences,
            info.shards.len()
        );
    }
    println!("  wrote {}", out.join("manifest.json").display());
    Ok(())
}

fn load(dir: &DatasetDir) -> Result<(DatasetSpec, Vec<PlannedSequence>, Vec<ManifestRecord>)> {
    let spec = DatasetSpec::load(&dir.spec())?;
    let planned: Vec<PlannedSequence> = files::read_json_lines(&dir.plan(), "dataset plan")?;
    if !dir.manifest().exists() {
        bail!(
            "{} has no manifest.jsonl: the run is unfinished, or its shards are not merged (`dataset merge`)",
            dir.root.display()
        );
    }
    let records: Vec<ManifestRecord> = files::read_json_lines(&dir.manifest(), "dataset manifest")?;
    Ok((spec, planned, records))
}

/// Largest per-frame values in a recording's statistics: penetration, vertices inside,
/// stretch, self-intersections.
fn recorded_extremes(recording: &Recording) -> (f64, usize, f64, usize) {
    recording
        .stats
        .iter()
        .fold((0.0, 0, 0.0, 0), |(p, v, s, x), f| {
            (
                f64::max(p, f.max_penetration_m),
                v.max(f.vertices_inside),
                f64::max(s, f.max_edge_stretch),
                x.max(f.self_intersections),
            )
        })
}

/// Checks one record against its plan entry, its recording and the gates; returns problems.
fn check_record(
    dir: &DatasetDir,
    spec: &DatasetSpec,
    plan: Option<&&PlannedSequence>,
    r: &ManifestRecord,
) -> Vec<String> {
    let mut problems = Vec::new();
    let mut problem = |m: String| problems.push(format!("{}: {m}", r.id));
    let Some(p) = plan else {
        problem("not in the plan".into());
        return problems;
    };
    if (
        &p.split, &p.garment, &p.motion, p.seed, &p.betas, p.material,
    ) != (
        &r.split, &r.garment, &r.motion, r.seed, &r.betas, r.material,
    ) {
        problem("split, garment, motion, seed, shape or material differ from the plan".into());
    }
    let Some(last) = r.attempts.last() else {
        problem("no attempts recorded".into());
        return problems;
    };
    if r.ok() != last.gates.passed || (r.status != "ok" && r.status != "failed") {
        problem(format!(
            "status '{}' disagrees with the last attempt's gates",
            r.status
        ));
    }
    if r.ok() && r.file.is_none() {
        problem("passed but has no recording".into());
    }
    if let Err(e) = r.check_paths() {
        problem(e);
        return problems;
    }
    let Some(file) = &r.file else {
        return problems;
    };
    let path = dir.root.join(file);
    match files::sha256_file(&path) {
        Err(e) => {
            problem(format!("recording {file} is unreadable: {e:#}"));
            return problems;
        }
        Ok((sha, bytes)) => {
            if Some(&sha) != r.sha256.as_ref() || bytes != r.bytes {
                problem(format!(
                    "recording {file} does not match its checksum or size"
                ));
            }
        }
    }
    let recording = match Recording::read(&path) {
        Ok(rec) => rec,
        Err(e) => {
            problem(format!("{e}"));
            return problems;
        }
    };
    let meta = recording.meta.as_ref().expect("checked by the reader");
    if recording.garment.len() != r.frames || meta.frames != r.frames {
        problem(format!(
            "recording has {} frames, the record {}",
            recording.garment.len(),
            r.frames
        ));
    }
    if recording.template.positions.len() != r.vertices {
        problem("vertex count differs from the record".into());
    }
    if meta.seed != Some(r.seed) || meta.betas != r.betas {
        problem("recording's seed or shape differs from the record".into());
    }
    let (pen, inside, stretch, crossings) = recorded_extremes(&recording);
    let g = &last.gates;
    if !last.gates.timed_out
        && ((pen - g.max_penetration_m).abs() > 1e-9
            || inside != g.max_verts_inside
            || (stretch - g.max_edge_stretch).abs() > 1e-9
            || crossings != g.max_self_intersections)
    {
        problem("gate values differ from the recording's statistics".into());
    }
    if r.ok() {
        let gates = &spec.gates;
        let allowed = (gates.max_inside_fraction * r.vertices as f64).floor() as usize;
        if pen > gates.max_penetration_m
            || inside > allowed
            || stretch > gates.max_edge_stretch
            || crossings > gates.max_self_intersections
        {
            problem("marked ok but its statistics break the spec's gates".into());
        }
    }
    problems
}

fn verify(root: &Path, json: Option<&Path>) -> Result<()> {
    let dir = DatasetDir::new(root);
    let (spec, planned, records) = load(&dir)?;
    let by_id: HashMap<&str, &PlannedSequence> =
        planned.iter().map(|p| (p.id.as_str(), p)).collect();
    let mut problems = Vec::new();
    let mut seen = HashSet::new();
    for r in &records {
        if !seen.insert(r.id.as_str()) {
            problems.push(format!("{}: listed twice in the manifest", r.id));
        }
    }
    let missing: Vec<&str> = planned
        .iter()
        .map(|p| p.id.as_str())
        .filter(|id| !seen.contains(id))
        .collect();
    if !missing.is_empty() {
        problems.push(format!(
            "{} planned sequences are not in the manifest (first: {})",
            missing.len(),
            missing[0]
        ));
    }
    for r in &records {
        problems.extend(check_record(&dir, &spec, by_id.get(r.id.as_str()), r));
    }
    let listed: HashSet<String> = records.iter().filter_map(|r| r.file.clone()).collect();
    if let Ok(entries) = std::fs::read_dir(dir.root.join("sequences")) {
        for e in entries.flatten() {
            let name = format!("sequences/{}", e.file_name().to_string_lossy());
            if !listed.contains(&name) {
                problems.push(format!("{name}: a file the manifest does not list"));
            }
        }
    }
    let ok = records.iter().filter(|r| r.ok()).count();
    println!(
        "verify {}: {} sequences in the manifest ({} planned), {ok} passed their gates, {} failed (recorded with reasons)",
        root.display(),
        records.len(),
        planned.len(),
        records.len() - ok
    );
    for p in problems.iter().take(50) {
        println!("  problem: {p}");
    }
    if let Some(path) = json {
        write_json(
            path,
            &serde_json::json!({"sequences": records.len(), "planned": planned.len(), "passed": ok,
                "problems": problems, "ok": problems.is_empty()}),
        )?;
    }
    if !problems.is_empty() {
        bail!(
            "{}: {} problems found (first: {})",
            root.display(),
            problems.len(),
            problems[0]
        );
    }
    println!("  every checksum, schema, count and gate result checks out");
    Ok(())
}

fn stats_cmd(root: &Path, json: Option<&Path>) -> Result<()> {
    let dir = DatasetDir::new(root);
    let (spec, _, records) = load(&dir)?;
    let s = stats(&records, sim::scene::FPS);
    println!(
        "dataset '{}' in {}: {} sequences ({} failed, {} retried), {} frames = {:.2} hours at 30 fps",
        spec.name,
        root.display(),
        s["sequences"],
        s["failed"],
        s["retried"],
        s["frames"],
        s["hours"].as_f64().unwrap_or(0.0)
    );
    for key in ["splits", "garments", "motions", "failures"] {
        let Some(map) = s[key].as_object() else {
            continue;
        };
        let row: Vec<String> = map.iter().map(|(k, v)| format!("{k} {v}")).collect();
        println!(
            "  {key:<9} {}",
            if row.is_empty() {
                "-".into()
            } else {
                row.join(", ")
            }
        );
    }
    for (name, h) in s["material_histograms"].as_object().into_iter().flatten() {
        println!(
            "  {name:<14} {:>10.4} .. {:<10.4} {}{}",
            h["min"].as_f64().unwrap_or(f64::NAN),
            h["max"].as_f64().unwrap_or(f64::NAN),
            h["counts"]
                .as_array()
                .map(|c| c
                    .iter()
                    .map(|v| v.to_string())
                    .collect::<Vec<_>>()
                    .join(" "))
                .unwrap_or_default(),
            if h["log10"] == true { " (log10)" } else { "" }
        );
    }
    println!(
        "  simulation: {:.0} s of wall time in all, {:.1} frames/s per sequence worker",
        s["simulation_wall_s"].as_f64().unwrap_or(0.0),
        s["simulated_frames_per_s"].as_f64().unwrap_or(0.0)
    );
    if let Some(path) = json {
        write_json(path, &s)?;
    }
    Ok(())
}

/// Copies `from` to `to` atomically unless they are the same file.
fn copy_into(from: &Path, to: &Path) -> Result<()> {
    if from == to || (to.exists() && std::fs::canonicalize(from)? == std::fs::canonicalize(to)?) {
        return Ok(());
    }
    crate::output::write_atomic(to, |w| {
        use std::io::Read;
        let (f, len) = files::open(from)?;
        std::io::copy(&mut f.take(len), w)?;
        Ok(())
    })
}

fn merge(out: &Path, roots: &[std::path::PathBuf]) -> Result<()> {
    let dirs: Vec<DatasetDir> = roots.iter().map(|r| DatasetDir::new(r)).collect();
    let spec = DatasetSpec::load(&dirs[0].spec())?;
    for d in &dirs[1..] {
        if DatasetSpec::load(&d.spec())? != spec {
            bail!(
                "{} and {} hold different specs: they are not shards of one dataset",
                dirs[0].root.display(),
                d.root.display()
            );
        }
    }
    let planned: Vec<PlannedSequence> = files::read_json_lines(&dirs[0].plan(), "dataset plan")?;
    // Find every planned sequence's finished record before writing anything.
    let mut found = Vec::with_capacity(planned.len());
    let mut missing = Vec::new();
    for p in &planned {
        match dirs
            .iter()
            .find_map(|d| finished_record(d, &p.id).map(|r| (d, r)))
        {
            Some(hit) => found.push(hit),
            None => missing.push(p.id.as_str()),
        }
    }
    if !missing.is_empty() {
        bail!(
            "{} of {} planned sequences have no finished record in {} (first: {}); finish those shards first",
            missing.len(),
            planned.len(),
            roots
                .iter()
                .map(|r| r.display().to_string())
                .collect::<Vec<_>>()
                .join(", "),
            missing[0]
        );
    }
    let target = DatasetDir::new(out);
    std::fs::create_dir_all(out)?;
    copy_into(&dirs[0].spec(), &target.spec())?;
    copy_into(&dirs[0].plan(), &target.plan())?;
    let mut records = Vec::with_capacity(found.len());
    for (d, r) in found {
        r.check_paths()
            .map_err(|e| anyhow::anyhow!("{}: {e}", d.manifest().display()))?;
        if let Some(file) = &r.file {
            copy_into(&d.root.join(file), &target.root.join(file))?;
        }
        let template = d.template(&r.garment);
        if template.exists() {
            copy_into(&template, &target.template(&r.garment))?;
        }
        copy_into(&d.record(&r.id), &target.record(&r.id))?;
        records.push(r);
    }
    files::write_json_lines(&target.manifest(), &records)?;
    println!(
        "merge: {} sequences from {} folders into {}",
        records.len(),
        dirs.len(),
        target.manifest().display()
    );
    Ok(())
}
