//! `dit-garment evaluate`: a model scored over a dataset's held-out splits beside the
//! baselines, per sequence in parallel, each sequence's result cached in the report folder
//! (a rerun with the same settings reuses it); JSON and the report
//! (`surrogate::evaluate::report`).

use std::time::Instant;

use anyhow::{Context, Result, bail};
use dataset::{DatasetDir, ManifestRecord};
use serde_json::{Value, json};
use surrogate::burn::prelude::Device;
use surrogate::evaluate::baselines::{Baseline, FloorMaps};
use surrogate::evaluate::family::fill_families;
use surrogate::evaluate::tables::{
    SequenceResult, SplitRows, aggregate, aggregate_by, grouped_text_table, text_table,
};
use surrogate::evaluate::{Evaluation, describe_model, document, fingerprint, select};
use surrogate::predict::{Predictor, Settings};
use surrogate::run::TrainedModel;

use crate::cli::EvaluateArgs;
use crate::run::{progress, set_threads};
use files::write_json;
use surrogate::evaluate::report::{self, Pictures};

pub fn run(args: &EvaluateArgs) -> Result<()> {
    set_threads(args.threads)?;
    if args.json.is_none() && args.report.is_none() {
        bail!("nothing to write: give --json F and/or --report DIR");
    }
    check_flags(args)?;
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
    settings.validate().context("bad sampler settings")?;
    let body = sim::sources::body_model(args.body_model.as_deref())?;
    let predictor = trained
        .as_ref()
        .map(|t| Predictor::new(t, &body))
        .transpose()?;
    let floor = FloorMaps::of(trained.as_ref());
    let baselines = args
        .baselines
        .iter()
        .filter(|b| !b.is_empty())
        .map(|b| Baseline::parse(b, floor))
        .collect::<surrogate::Result<Vec<_>>>()?;
    if trained.is_none() && baselines.is_empty() {
        bail!("--model none with no --baselines: nothing to score (name a model or a baseline)");
    }

    let dir = DatasetDir::new(&args.data);
    let manifest = dir.manifest();
    let all: Vec<ManifestRecord> = files::read_json_lines(&manifest, "dataset manifest")
        .with_context(|| format!("reading the dataset in {}", args.data.display()))?;
    let records = select(&all, &args.splits, args.max_sequences, &manifest)?;
    let (model_json, identity) = match &trained {
        Some(t) => {
            let (described, identity) = describe_model(t)?;
            (described, Some(identity))
        }
        None => (Value::Null, None),
    };
    let fingerprint = fingerprint(identity.as_ref(), &settings, &baselines, floor, &body);
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
    let done = |id: &str| {
        bar.set_message(id.to_string());
        bar.inc(1);
    };
    let (mut results, reused) = evaluation.all(&records, cache.as_deref(), &done)?;
    bar.finish_and_clear();
    fill_families(&mut results, &args.data, &body)?;
    let asked =
        json!({"splits": args.splits, "max_sequences": args.max_sequences, "data": args.data});
    let rows = aggregate(&results);
    let output = document(&results, &rows, model_json, &settings, asked);
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
    print_tables(&results, &rows.0, started, reused)
}

/// The flags' own mistakes, before the dataset is read (and blamed).
fn check_flags(args: &EvaluateArgs) -> Result<()> {
    if args.max_sequences == Some(0) {
        bail!("--max-sequences 0: score at least 1 sequence (or leave the flag out for all)");
    }
    if args.splits.iter().any(|s| s.trim().is_empty()) {
        bail!("--splits holds an empty name: give split names, comma-separated");
    }
    Ok(())
}

/// The split table, then per garment family and per motion within each split where a split
/// has several.
fn print_tables(
    results: &[SequenceResult],
    splits: &SplitRows,
    started: Instant,
    reused: usize,
) -> Result<()> {
    say!(
        "evaluate: {} sequences of {} splits in {:.1} s ({} reused from the cache)",
        results.len(),
        splits.len(),
        started.elapsed().as_secs_f64(),
        reused
    );
    say_part!("{}", text_table(splits));
    for (label, groups) in [
        ("family", aggregate_by(results, |r| r.family.clone())),
        (
            "motion",
            aggregate_by(results, |r| motions::short_label(&r.motion).to_string()),
        ),
    ] {
        if groups.values().any(|g| g.len() > 1) {
            say_part!("\n{}", grouped_text_table(label, &groups));
        }
    }
    Ok(())
}
