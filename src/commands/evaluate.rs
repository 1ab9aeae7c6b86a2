//! `dit-garment evaluate`: a model scored over a dataset's held-out splits beside the
//! baselines, per sequence in parallel, each sequence's result cached in the report folder
//! (a rerun with the same settings reuses it); JSON and the report
//! (`surrogate::evaluate::report`).

use std::time::Instant;

use anyhow::{Context, Result, bail};
use rayon::prelude::*;
use serde_json::{Value, json};
use sim::dataset::{DatasetDir, ManifestRecord};
use surrogate::burn::prelude::Device;
use surrogate::evaluate::baselines::{Baseline, FloorMaps};
use surrogate::evaluate::tables::{SequenceResult, SplitRows, aggregate, paper_numbers};
use surrogate::evaluate::{Evaluation, select, units};
use surrogate::predict::{Predictor, Settings};
use surrogate::run::TrainedModel;

use crate::cli::EvaluateArgs;
use crate::output::write_json;
use crate::run::{progress, set_threads};
use surrogate::evaluate::report::{self, Pictures};

pub fn run(args: &EvaluateArgs) -> Result<()> {
    set_threads(args.threads)?;
    if args.json.is_none() && args.report.is_none() {
        bail!("nothing to write: give --json F and/or --report DIR");
    }
    let trained = match args.model.as_str() {
        "none" => None,
        name => Some(TrainedModel::load_named(name, &Device::flex())?),
    };
    let defaults = trained
        .as_ref()
        .map_or_else(Settings::default, Settings::for_model);
    let settings = Settings {
        // The scores come from the predicted vertices; the sampler's own inside test would
        // only cost time.
        inside_test: false,
        ..args.sampler.settings(defaults)
    };
    if let Err(e) = settings.validate() {
        bail!("bad sampler settings: {e}");
    }
    let body = sim::sources::body_model(args.body_model.as_deref())?;
    let predictor = trained
        .as_ref()
        .map(|t| Predictor::new(t, &body))
        .transpose()?;
    let floor = trained
        .as_ref()
        .map_or(FloorMaps::default(), |t| FloorMaps {
            resolution: t.data.resolution,
            target: t.data.target,
            root: t.data.root,
        });
    let baselines = args
        .baselines
        .iter()
        .filter(|b| !b.is_empty())
        .map(|b| Baseline::parse(b, floor))
        .collect::<surrogate::Result<Vec<_>>>()?;

    let dir = DatasetDir::new(&args.data);
    let manifest = dir.manifest();
    let all: Vec<ManifestRecord> = files::read_json_lines(&manifest, "dataset manifest")
        .with_context(|| format!("reading the dataset in {}", args.data.display()))?;
    let records = select(&all, &args.splits, args.max_sequences, &manifest)?;
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
    let evaluation = Evaluation {
        data: &args.data,
        body: &body,
        predictor: predictor.as_ref(),
        settings,
        baselines,
        fingerprint,
    };
    let cache = args.report.as_ref().map(|r| r.join("sequences"));
    let rest = "({elapsed}, eta {eta}) {msg}";
    let bar = progress("evaluating", records.len(), "sequences", rest, args.quiet);
    let started = Instant::now();
    let results = records
        .par_iter()
        .map(|record| {
            let file = cache
                .as_ref()
                .map(|d| d.join(format!("{}.json", record.id)));
            if let Some(hit) = file.as_deref().and_then(|f| evaluation.cached(f, record)) {
                bar.inc(1);
                return Ok((hit, true));
            }
            let result = evaluation
                .sequence(record)
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
        "units": units(),
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
    print_table(&splits);
    Ok(())
}

/// Prints the short table of `evaluate`.
pub fn print_table(splits: &SplitRows) {
    println!(
        "{:<14} {:<18} {:>8} {:>8} {:>9} {:>8} {:>8} {:>8}",
        "split", "method", "E_v cm", "E_c %", "inside %", "stretch", "jitter", "fps"
    );
    for (s, methods) in splits {
        for (m, r) in methods {
            println!(
                "{:<14} {:<18} {:>8.3} {:>8.3} {:>9.3} {:>8.3} {:>8.4} {:>8.1}",
                s,
                m.name(),
                r.scores.E_v,
                r.scores.E_c,
                r.inside_percent,
                r.stretch_p99,
                r.jitter,
                r.fps
            );
        }
    }
}
