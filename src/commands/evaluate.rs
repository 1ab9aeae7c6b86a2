//! `dit-garment evaluate`: a model scored over a dataset's held-out splits beside the
//! baselines, per sequence in parallel, each sequence's result cached in the report folder
//! (a rerun with the same settings reuses it); JSON and the report (`crate::report`).

use std::collections::BTreeMap;
use std::path::Path;
use std::time::Instant;

use anyhow::{Context, Result, bail};
use indicatif::{ProgressBar, ProgressDrawTarget, ProgressStyle};
use motions::BodyModel;
use rayon::prelude::*;
use serde_json::{Value, json};
use sim::dataset::{DatasetDir, ManifestRecord};
use surrogate::burn::prelude::Device;
use surrogate::data::Sequence;
use surrogate::evaluate::baselines::{self, Baseline, FloorMaps};
use surrogate::evaluate::tables::{SequenceResult, aggregate, paper_numbers};
use surrogate::evaluate::{Method, Truth, UNITS};
use surrogate::geometry::{RootRemoval, TargetKind};
use surrogate::predict::{BodySequence, Guidance, Predictor, Settings};
use surrogate::train::TrainedModel;

use crate::cli::EvaluateArgs;
use crate::output::write_json;
use crate::prediction::model_dir;
use crate::report::{self, Pictures};
use crate::run::set_threads;

/// What evaluating a sequence needs.
pub struct EvalContext<'a> {
    pub data: &'a Path,
    pub body: &'a BodyModel,
    pub predictor: Option<&'a Predictor<'a>>,
    pub settings: Settings,
    pub baselines: Vec<(Method, Baseline)>,
    pub fingerprint: Value,
}

fn baseline(name: &str, floor: FloorMaps) -> Result<(Method, Baseline)> {
    Ok(match name {
        "lbs" => (Method::Lbs, Baseline::Lbs),
        "lbs_nearest" => (Method::LbsNearest, Baseline::LbsNearest),
        "floor" => (Method::Floor, Baseline::Floor(floor)),
        "rest" => (Method::Rest, Baseline::Rest),
        other => bail!("unknown baseline '{other}' (lbs, lbs_nearest, floor, rest)"),
    })
}

/// Scores one sequence with every method.
fn evaluate_one(c: &EvalContext, record: &ManifestRecord) -> Result<SequenceResult> {
    let file = record
        .file
        .as_deref()
        .with_context(|| format!("sequence {} has no recording", record.id))?;
    let path = c.data.join(file);
    if let Some(expected) = &record.sha256 {
        let (sha, _) = files::sha256_file(&path)?;
        if &sha != expected {
            bail!(
                "{}: does not match the manifest's checksum (damaged or replaced)",
                path.display()
            );
        }
    }
    let seq = Sequence::read(&path)?;
    let truth = Truth::new(&seq, c.body, 0).with_context(|| path.display().to_string())?;
    let frames = truth.frames();
    let mut methods = BTreeMap::new();
    for &(method, b) in &c.baselines {
        let started = Instant::now();
        let predicted = baselines::predict(b, c.body, &seq, frames)?;
        let fps = frames.len() as f64 / started.elapsed().as_secs_f64().max(1e-9);
        methods.insert(method, truth.score(&predicted, fps));
    }
    if let Some(predictor) = c.predictor {
        let mut garment = predictor.garment(&seq.template)?;
        let motion = seq.motion()?;
        let body = BodySequence {
            motion: &motion,
            betas: &seq.betas,
            material: seq.meta.material,
        };
        let range = frames[0]..frames[frames.len() - 1] + 1;
        for (method, weight) in [
            (Method::Model, c.settings.guidance.weight),
            (Method::ModelNoGuidance, 0.0),
        ] {
            let settings = Settings {
                guidance: Guidance {
                    weight,
                    ..c.settings.guidance
                },
                ..c.settings
            };
            let mut predicted = Vec::with_capacity(frames.len());
            let timing =
                predictor.predict(&mut garment, &body, range.clone(), &settings, &mut |f| {
                    predicted.push(f.garment.clone());
                    Ok(())
                })?;
            let fps = frames.len() as f64 / timing.wall_s.max(1e-9);
            methods.insert(method, truth.score(&predicted, fps));
        }
    }
    Ok(SequenceResult {
        id: record.id.clone(),
        split: record.split.clone(),
        garment: record.garment.clone(),
        motion: record.motion.clone(),
        file: file.to_string(),
        settings: sequence_fingerprint(&c.fingerprint, record),
        methods,
        simulation: truth.simulation(),
    })
}

/// The settings of one sequence's rows: the run's, and the recording they scored.
fn sequence_fingerprint(run: &Value, record: &ManifestRecord) -> Value {
    json!({"run": run, "file": record.file, "sha256": record.sha256, "split": record.split})
}

/// A cached result made with the same settings on the same recording, if any.
fn cached(path: &Path, run: &Value, record: &ManifestRecord) -> Option<SequenceResult> {
    let text = std::fs::read_to_string(path).ok()?;
    let r: SequenceResult = serde_json::from_str(&text).ok()?;
    (r.settings == sequence_fingerprint(run, record) && r.split == record.split).then_some(r)
}

pub fn run(args: &EvaluateArgs) -> Result<()> {
    set_threads(args.threads)?;
    if args.json.is_none() && args.report.is_none() {
        bail!("nothing to write: give --json F and/or --report DIR");
    }
    let trained = match args.model.as_str() {
        "none" => None,
        name => {
            let dir = model_dir(name)?;
            Some(
                TrainedModel::load(&dir, &Device::flex())
                    .with_context(|| format!("loading the model in {}", dir.display()))?,
            )
        }
    };
    let defaults = trained
        .as_ref()
        .map_or_else(Settings::default, Settings::for_model);
    let settings = Settings {
        steps: args.steps.unwrap_or(defaults.steps),
        guidance: Guidance {
            weight: args.guidance,
            start: args.guidance_start.unwrap_or(defaults.guidance.start),
            refine: args.guidance_refine.unwrap_or(defaults.guidance.refine),
            ..Guidance::default()
        },
        seed: args.seed,
        batch: args.batch,
        draws: args.draws,
        // The scores come from the predicted vertices; the sampler's own inside test would
        // only cost time.
        inside_test: false,
        ..Settings::default()
    };
    if let Err(e) = settings.validate() {
        bail!("bad sampler settings: {e}");
    }
    let body = sim::sources::body_model(args.body_model.as_deref())?;
    let predictor = trained
        .as_ref()
        .map(|t| Predictor::new(t, &body))
        .transpose()?;
    let floor = trained.as_ref().map_or(
        FloorMaps {
            resolution: 64,
            target: TargetKind::LbsResidual,
            root: RootRemoval::Heading,
        },
        |t| FloorMaps {
            resolution: t.data.resolution,
            target: t.data.target,
            root: t.data.root,
        },
    );
    let baselines = args
        .baselines
        .iter()
        .filter(|b| !b.is_empty())
        .map(|b| baseline(b, floor))
        .collect::<Result<Vec<_>>>()?;

    let dir = DatasetDir::new(&args.data);
    let manifest = dir.manifest();
    let all: Vec<ManifestRecord> = files::read_json_lines(&manifest, "dataset manifest")
        .with_context(|| format!("reading the dataset in {}", args.data.display()))?;
    let mut records = Vec::new();
    let mut splits_asked: Vec<&String> = Vec::new();
    for split in &args.splits {
        if splits_asked.contains(&split) {
            continue;
        }
        splits_asked.push(split);
        let mut of_split: Vec<ManifestRecord> = all
            .iter()
            .filter(|r| r.ok() && &r.split == split)
            .cloned()
            .collect();
        if let Some(k) = args.max_sequences {
            of_split.truncate(k);
        }
        records.extend(of_split);
    }
    if let Some(bad) = records
        .iter()
        .find(|r| r.id.is_empty() || r.id.contains(['/', '\\']) || r.id.starts_with('.'))
    {
        bail!(
            "{}: sequence id '{}' is not a plain file name",
            manifest.display(),
            bad.id
        );
    }
    if records.is_empty() {
        bail!(
            "{}: no finished sequences in the splits {}",
            manifest.display(),
            args.splits.join(", ")
        );
    }
    let weights = trained
        .as_ref()
        .map(|t| files::sha256_file(&t.run.join("model.safetensors")))
        .transpose()?
        .map(|(sha, _)| sha);
    let model_json = match &trained {
        Some(t) => json!({
            "run": t.run, "weights_sha256": weights, "target": t.data.target.name(),
            "resolution": t.data.resolution, "config": t.config,
            "trained_on": t.data.templates.iter().filter(|t| t.in_training()).map(|t| &t.name).collect::<Vec<_>>(),
        }),
        None => Value::Null,
    };
    // What makes the predictions: the weights and their config, not the folder they are in.
    let identity = trained.as_ref().map(|t| {
        json!({"weights_sha256": weights, "target": t.data.target.name(),
               "resolution": t.data.resolution, "config": t.config})
    });
    let fingerprint = json!({
        "model": identity, "steps": settings.steps, "guidance": settings.guidance,
        "seed": settings.seed, "batch": settings.batch, "draws": settings.draws,
        "baselines": baselines.iter().map(|(m, _)| m.name()).collect::<Vec<_>>(),
        "floor": {"resolution": floor.resolution, "target": floor.target.name()},
        "body_model": body.name(), "threads": rayon::current_num_threads(),
        "software": env!("CARGO_PKG_VERSION"),
    });
    let context = EvalContext {
        data: &args.data,
        body: &body,
        predictor: predictor.as_ref(),
        settings,
        baselines,
        fingerprint: fingerprint.clone(),
    };
    let cache = args.report.as_ref().map(|r| r.join("sequences"));
    let bar = ProgressBar::new(records.len() as u64).with_style(
        ProgressStyle::with_template(
            "evaluating [{bar:30}] {pos}/{len} sequences ({elapsed}, eta {eta}) {msg}",
        )?
        .progress_chars("=> "),
    );
    if args.quiet {
        bar.set_draw_target(ProgressDrawTarget::hidden());
    }
    let started = Instant::now();
    let results = records
        .par_iter()
        .map(|record| {
            let file = cache
                .as_ref()
                .map(|d| d.join(format!("{}.json", record.id)));
            if let Some(hit) = file
                .as_deref()
                .and_then(|f| cached(f, &fingerprint, record))
            {
                bar.inc(1);
                return Ok((hit, true));
            }
            let result = evaluate_one(&context, record)
                .with_context(|| format!("evaluating sequence {}", record.id))?;
            if let Some(f) = &file {
                write_json(f, &result)?;
            }
            bar.set_message(record.id.clone());
            bar.inc(1);
            Ok((result, false))
        })
        .collect::<Result<Vec<_>>>()?;
    bar.finish_and_clear();
    let reused = results.iter().filter(|(_, hit)| *hit).count();
    let results: Vec<SequenceResult> = results.into_iter().map(|(r, _)| r).collect();
    let (splits, simulation) = aggregate(&results);
    let units: serde_json::Map<String, Value> = UNITS
        .iter()
        .map(|(k, u)| (k.to_string(), json!(u)))
        .collect();
    let settings_json = json!({
        "steps": settings.steps, "guidance": settings.guidance.weight,
        "guidance_start": settings.guidance.start, "seed": settings.seed,
        "batch": settings.batch, "draws": settings.draws, "threads": rayon::current_num_threads(),
        "splits": args.splits, "max_sequences": args.max_sequences,
        "data": args.data, "protocol": "motion frames (after blend-in and settle); every 5th scored, averaged over frames then sequences; jitter over all motion frames",
    });
    let output = json!({
        "splits": splits,
        "simulation": simulation,
        "sequences": results,
        "model": model_json,
        "settings": settings_json,
        "units": units,
        "paper": paper_numbers(),
    });
    if let Some(path) = &args.json {
        write_json(path, &output)?;
    }
    if let Some(dir) = &args.report {
        let pictures = Pictures {
            data: &args.data,
            body: &body,
            predictor: predictor.as_ref(),
            settings,
        };
        report::write(dir, &output, &results, &pictures)
            .with_context(|| format!("writing the report in {}", dir.display()))?;
    }
    println!(
        "evaluate: {} sequences of {} splits in {:.1} s ({} reused from the cache)",
        results.len(),
        splits.len(),
        started.elapsed().as_secs_f64(),
        reused
    );
    report::print_table(&splits);
    Ok(())
}
