//! The evaluation protocol over a dataset folder: which sequences a run scores (finished ones
//! of the asked splits, in manifest order), each sequence's recording checked against the
//! manifest and scored with every method (the baselines, the model with and without
//! guidance), and a sequence's result reused when it was made with the same settings on the
//! same recording. Threads, progress and files are the caller's.

use std::collections::BTreeMap;
use std::path::Path;
use std::time::Instant;

use dataset::ManifestRecord;
use motions::BodyModel;
use rayon::prelude::*;
use serde_json::{Value, json};

use super::baselines::{self, Baseline, FloorMaps};
use super::tables::{Rows, SequenceResult, aggregate_by, paper_numbers};
use super::{Method, Truth};
use crate::data::Sequence;
use crate::error::{Error, Result, bad_value, file_error};
use crate::predict::{BodySequence, Guidance, Predictor, Settings};
use crate::run::TrainedModel;

impl Baseline {
    /// The baseline a name asks for (`lbs`, `lbs_nearest`, `floor` with `floor`'s maps,
    /// `rest`), with its method.
    pub fn parse(name: &str, floor: FloorMaps) -> Result<(Method, Baseline)> {
        Ok(match name {
            "lbs" => (Method::Lbs, Baseline::Lbs),
            "lbs_nearest" => (Method::LbsNearest, Baseline::LbsNearest),
            "floor" => (Method::Floor, Baseline::Floor(floor)),
            "rest" => (Method::Rest, Baseline::Rest),
            other => {
                return Err(bad_value(
                    "--baselines",
                    other,
                    "unknown baseline (lbs, lbs_nearest, floor, rest)",
                ));
            }
        })
    }
}

/// The finished sequences of `splits` (each split once, in the order asked; at most `max` of
/// each), from the records of the manifest at `manifest`. None, or an id that is not a plain
/// file name (results are cached by id), is an error naming the manifest.
pub fn select(
    all: &[ManifestRecord],
    splits: &[String],
    max: Option<usize>,
    manifest: &Path,
) -> Result<Vec<ManifestRecord>> {
    let mut records = Vec::new();
    let mut asked: Vec<&String> = Vec::new();
    for split in splits {
        if asked.contains(&split) {
            continue;
        }
        asked.push(split);
        let of_split = all
            .iter()
            .filter(|r| r.ok() && r.sequence.split.name() == split)
            .cloned();
        records.extend(of_split.take(max.unwrap_or(usize::MAX)));
    }
    // A sequence listed twice (a manifest concatenated with itself, say) would count twice.
    for (k, r) in records.iter().enumerate() {
        if records[..k].iter().any(|o| o.sequence.id == r.sequence.id) {
            let line = all
                .iter()
                .filter(|o| o.sequence.id == r.sequence.id)
                .count();
            let problem = format!("sequence '{}' is listed {line} times", r.sequence.id);
            return Err(file_error(manifest, problem));
        }
    }
    // Ids become file names (the cache, per-sequence outputs): the dataset's one check.
    for r in &records {
        r.check_paths().map_err(|e| file_error(manifest, e))?;
    }
    if records.is_empty() {
        let problem = format!("no finished sequences in the splits {}", splits.join(", "));
        return Err(file_error(manifest, problem));
    }
    Ok(records)
}

/// What `evaluate` records of a model (`model` in its JSON: the run folder, the weights'
/// SHA-256 (an ensemble's members' too), target, resolution, configuration and the templates
/// trained on), and the part of that which makes its predictions (the weights and their
/// configuration, not the folder they are in) for the results' [`fingerprint`].
pub fn describe_model(t: &TrainedModel) -> Result<(Value, Value)> {
    let mut shas = Vec::new();
    for run in &t.networks {
        shas.push(files::sha256_file(&run.join("model.safetensors"))?.0);
    }
    let mut identity = json!({"weights_sha256": shas[0], "target": t.data.target.name(),
        "resolution": t.data.resolution, "config": t.config});
    if shas.len() > 1 {
        // An ensemble: every member's weights make its predictions.
        identity["members_weights_sha256"] = json!(shas[1..]);
    }
    let mut described = identity.clone();
    described["run"] = json!(t.run);
    if t.networks.len() > 1 {
        described["members"] = json!(t.networks);
    }
    described["trained_on"] = t
        .data
        .templates
        .iter()
        .filter(|t| t.in_training())
        .map(|t| json!(t.name))
        .collect();
    Ok((described, identity))
}

/// What makes a sequence's result, so a cached one made otherwise is made again: the model's
/// identity ([`describe_model`]), the sampler, the baselines and floor maps, the body model,
/// the thread count and the software version.
pub fn fingerprint(
    model: Option<&Value>,
    settings: &Settings,
    baselines: &[(Method, Baseline)],
    floor: FloorMaps,
    body: &BodyModel,
) -> Value {
    json!({
        "model": model, "steps": settings.steps, "guidance": settings.guidance,
        "seed": settings.seed, "batch": settings.batch, "draws": settings.draws,
        "baselines": baselines.iter().map(|(m, _)| m.name()).collect::<Vec<_>>(),
        "floor": {"resolution": floor.resolution, "target": floor.target.name()},
        "body_model": body.name(), "threads": rayon::current_num_threads(),
        "software": env!("CARGO_PKG_VERSION"),
    })
}

/// The whole of an evaluation as `evaluate --json` writes it: the rows of every split and the
/// simulation's (`rows`, [`super::tables::aggregate`] of `results`), the rows of every garment
/// family and every motion within each split, every sequence's result, the model
/// ([`describe_model`]), the settings (`settings`, to which the sampler's and the protocol are
/// added), the units and the paper's numbers.
pub fn document(
    results: &[SequenceResult],
    rows: &Rows,
    model: Value,
    sampler: &Settings,
    mut settings: Value,
) -> Value {
    let (splits, simulation) = rows;
    for (key, value) in [
        ("steps", json!(sampler.steps)),
        ("guidance", json!(sampler.guidance.weight)),
        ("guidance_start", json!(sampler.guidance.start)),
        ("seed", json!(sampler.seed)),
        ("batch", json!(sampler.batch)),
        ("draws", json!(sampler.draws)),
        ("threads", json!(rayon::current_num_threads())),
        ("protocol", json!(PROTOCOL)),
    ] {
        settings[key] = value;
    }
    let families = aggregate_by(results, |r| r.family.clone());
    let motions = aggregate_by(results, |r| r.motion.clone());
    let family_of_garment: BTreeMap<&str, &str> = results
        .iter()
        .map(|r| (r.garment.as_str(), r.family.as_str()))
        .collect();
    json!({
        "splits": splits, "families": families, "motions": motions,
        "family_of_garment": family_of_garment, "simulation": simulation,
        "sequences": results, "model": model, "settings": settings, "units": super::units(),
        "paper": paper_numbers(),
    })
}

/// What is scored, in words (the JSON's `settings.protocol`).
const PROTOCOL: &str = "motion frames (after blend-in and settle); every 5th scored, averaged \
                        over frames then sequences; jitter over all motion frames";

/// What scoring a sequence needs.
pub struct Evaluation<'a> {
    /// The dataset folder the records' files are in.
    pub data: &'a Path,
    /// The body model.
    pub body: &'a BodyModel,
    /// The model, if one is scored.
    pub predictor: Option<&'a Predictor<'a>>,
    /// The sampler's settings (its guidance weight is the `model` row's; `model_no_guidance`
    /// has none).
    pub settings: Settings,
    /// The baselines scored.
    pub baselines: Vec<(Method, Baseline)>,
    /// What makes a result: the run's settings (a cached result with other settings is made
    /// again).
    pub fingerprint: Value,
}

impl Evaluation<'_> {
    /// Scores one sequence with every method; its recording must match the manifest's
    /// checksum.
    pub fn sequence(&self, record: &ManifestRecord) -> Result<SequenceResult> {
        let file = record.file.as_deref().ok_or_else(|| Error::NoRecording {
            sequence: record.sequence.id.clone(),
        })?;
        let path = self.data.join(file);
        if let Some(expected) = &record.sha256 {
            let (sha, _) = files::sha256_file(&path)?;
            if &sha != expected {
                let problem = "does not match the manifest's checksum (damaged or replaced)";
                return Err(file_error(&path, problem));
            }
        }
        let seq = Sequence::read(&path)?;
        // Results are grouped by the manifest's labels: they must be the recording's own (a
        // garment file is recorded under its file name's stem).
        let stem = Path::new(&record.sequence.garment)
            .file_stem()
            .map(|s| s.to_string_lossy());
        let garment_agrees = seq.meta.garment == record.sequence.garment
            || stem.is_some_and(|s| s == seq.meta.garment);
        if !garment_agrees || seq.meta.motion != record.sequence.motion {
            return Err(file_error(
                &path,
                format!(
                    "holds '{}' on '{}', but the manifest's line for sequence {} says '{}' on '{}'",
                    seq.meta.garment,
                    seq.meta.motion,
                    record.sequence.id,
                    record.sequence.garment,
                    record.sequence.motion
                ),
            ));
        }
        let truth = Truth::new(&seq, self.body, 0).map_err(|e| file_error(&path, e))?;
        let frames = truth.frames();
        let mut methods = BTreeMap::new();
        for &(method, b) in &self.baselines {
            let started = Instant::now();
            let predicted = baselines::predict(b, self.body, &seq, frames)?;
            let fps = frames.len() as f64 / started.elapsed().as_secs_f64().max(1e-9);
            methods.insert(method, truth.score(&predicted, fps));
        }
        if let Some(predictor) = self.predictor {
            let mut garment = predictor.garment(&seq.template)?;
            let motion = seq.motion()?;
            let body = BodySequence {
                motion: &motion,
                betas: &seq.betas,
                material: seq.meta.material,
            };
            let range = frames[0]..frames[frames.len() - 1] + 1;
            for (method, weight) in [
                (Method::Model, self.settings.guidance.weight),
                (Method::ModelNoGuidance, 0.0),
            ] {
                let settings = Settings {
                    guidance: Guidance {
                        weight,
                        ..self.settings.guidance
                    },
                    ..self.settings
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
            id: record.sequence.id.clone(),
            split: record.sequence.split.to_string(),
            garment: record.sequence.garment.clone(),
            family: String::new(),
            motion: record.sequence.motion.clone(),
            file: file.to_string(),
            settings: self.settings_of(record),
            methods,
            simulation: truth.simulation(),
        })
    }

    /// A result cached at `path` that was made with this run's settings on the same
    /// recording, if any.
    pub fn cached(&self, path: &Path, record: &ManifestRecord) -> Option<SequenceResult> {
        let text = std::fs::read_to_string(path).ok()?;
        let r: SequenceResult = serde_json::from_str(&text).ok()?;
        (r.settings == self.settings_of(record) && r.split == record.sequence.split.name())
            .then_some(r)
    }

    /// Scores `records` in parallel, each result cached as `cache/<id>.json` when a cache
    /// folder is given (a result cached with this run's settings on the same recording is
    /// reused); `done(id)` is told after each. Returns the results in order and how
    /// many were reused.
    pub fn all(
        &self,
        records: &[ManifestRecord],
        cache: Option<&Path>,
        done: &(dyn Fn(&str) + Sync),
    ) -> Result<(Vec<SequenceResult>, usize)> {
        let results = records
            .par_iter()
            .map(|record| {
                let file = cache.map(|d| d.join(format!("{}.json", record.sequence.id)));
                if let Some(hit) = file.as_deref().and_then(|f| self.cached(f, record)) {
                    done(&record.sequence.id);
                    return Ok((hit, true));
                }
                let result = self.sequence(record).map_err(|e| Error::Sequence {
                    id: record.sequence.id.clone(),
                    source: Box::new(e),
                })?;
                if let Some(f) = &file {
                    files::write_json(f, &result)?;
                }
                done(&record.sequence.id);
                Ok((result, false))
            })
            .collect::<Result<Vec<_>>>()?;
        let reused = results.iter().filter(|(_, hit)| *hit).count();
        Ok((results.into_iter().map(|(r, _)| r).collect(), reused))
    }

    /// The settings of one sequence's rows: the run's, and the recording they scored.
    fn settings_of(&self, record: &ManifestRecord) -> Value {
        json!({"run": self.fingerprint, "file": record.file, "sha256": record.sha256, "split": record.sequence.split})
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn record(id: &str, split: &str, ok: bool) -> ManifestRecord {
        let mut r: ManifestRecord = serde_json::from_value(json!({
            "id": id, "split": split, "garment": "skirt", "motion": "walk", "betas": [],
            "material": {"k_s_n_per_m": 100.0, "rho_kg_per_m2": 0.2, "k_b_n_m": 1e-6},
            "friction": 0.3,
            "seed": 1, "frames": 10, "vertices": 4, "status": "ok", "attempts": [],
            "bytes": 0, "software": "test", "wall_s": 0.0
        }))
        .unwrap();
        if !ok {
            r.status = dataset::Status::Failed;
        }
        r
    }

    #[test]
    fn selection_keeps_finished_sequences_of_the_asked_splits_once() {
        let all = [
            record("a", "test", true),
            record("b", "test", false),
            record("c", "train", true),
            record("d", "test", true),
        ];
        let manifest = Path::new("m.jsonl");
        let splits = |s: &[&str]| s.iter().map(|s| s.to_string()).collect::<Vec<_>>();
        let ids = |r: Vec<ManifestRecord>| r.into_iter().map(|r| r.sequence.id).collect::<Vec<_>>();
        let picked = select(&all, &splits(&["test", "train", "test"]), None, manifest);
        assert_eq!(ids(picked.unwrap()), ["a", "d", "c"]);
        let one = select(&all, &splits(&["test"]), Some(1), manifest).unwrap();
        assert_eq!(ids(one), ["a"]);
        let e = select(&all, &splits(&["nope"]), None, manifest).unwrap_err();
        assert!(
            matches!(&e, Error::File { path, .. } if path == "m.jsonl"),
            "{e}"
        );
        assert!(e.to_string().contains("no finished sequences"), "{e}");
        let twice = [record("a", "test", true), record("a", "test", true)];
        let e = select(&twice, &splits(&["test"]), None, manifest).unwrap_err();
        assert!(e.to_string().contains("'a' is listed 2 times"), "{e}");
        let bad = [record("../x", "test", true)];
        let e = select(&bad, &splits(&["test"]), None, manifest).unwrap_err();
        assert!(e.to_string().contains("not a plain file name"), "{e}");
        let e = Baseline::parse("knn", FloorMaps::default()).unwrap_err();
        assert!(
            matches!(&e, Error::Value { key, value, .. } if key == "--baselines" && value == "knn"),
            "{e}"
        );
    }
}
