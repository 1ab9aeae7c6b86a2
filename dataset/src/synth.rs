//! Running a dataset's sequences: each simulated with the spec's solver settings, judged by its
//! gates and retried with the retry settings, its recording written whole; the folder checked
//! against its spec, what killed runs left removed, and the manifest written once every planned
//! sequence has a record. Which sequences a process runs (shards), in how many threads, and how
//! it shows progress are the caller's.

use std::collections::HashMap;
use std::path::Path;
use std::sync::Arc;
use std::time::{Duration, Instant};

use motions::BodyModel;
use rayon::prelude::*;

use super::{
    Attempt, DatasetDir, DatasetSpec, GateResult, ManifestRecord, PlannedSequence, finished_record,
};
use crate::error::{Error, Result};
use crate::split::Status;
use sim::BlowUpCause;
use sim::run::Prepared;
use sim::scene::BodyAttachment;
use sim::{SceneConfig, SolverParams};

/// A garment template with its body attachments, shared by every sequence that uses it.
pub type Template = (Arc<garments::Garment>, Vec<BodyAttachment>);

/// The templates of the garments `planned` uses, made (or read from `cache`) in parallel,
/// `making(name, path)` told before one is made. A template that fails its gates (a drawn
/// design can) comes back among the unusable with why, so its sequences fail rather than the
/// run; any other problem with a garment is an error.
pub fn make_templates(
    planned: &[&PlannedSequence],
    model: &BodyModel,
    cache: &Path,
    making: &(dyn Fn(&str, &Path) + Sync),
) -> Result<(HashMap<String, Template>, HashMap<String, String>)> {
    let mut names: Vec<&str> = planned.iter().map(|p| p.garment.as_str()).collect();
    names.sort();
    names.dedup();
    let made = names
        .par_iter()
        .map(
            |&name| match sim::sources::garment(name, model, cache, |path| making(name, path)) {
                Ok((garment, attachments)) => Ok((name, Ok((Arc::new(garment), attachments)))),
                Err(e @ sim::Error::TemplateGates { .. }) => Ok((name, Err(e.to_string()))),
                Err(e) => Err(Error::from(e)),
            },
        )
        .collect::<Result<Vec<_>>>()?;
    let (mut templates, mut unusable) = (HashMap::new(), HashMap::new());
    for (name, template) in made {
        match template {
            Ok(t) => {
                templates.insert(name.to_string(), t);
            }
            Err(why) => {
                unusable.insert(name.to_string(), why);
            }
        }
    }
    Ok((templates, unusable))
}

/// What every sequence of a run shares.
pub struct Synthesis<'a> {
    /// The dataset's spec.
    pub spec: &'a DatasetSpec,
    /// Its folder.
    pub dir: &'a DatasetDir,
    /// The body model.
    pub model: Arc<BodyModel>,
    /// The body model's file, recorded in every sequence's configuration (none: the default).
    pub model_file: Option<String>,
    /// The templates of the garments the run's sequences use, by name.
    pub templates: HashMap<String, Template>,
    /// Garments whose template could not be made, with why (a drawn design whose template
    /// failed its gates): their sequences are recorded as failed, not run.
    pub unusable: HashMap<String, String>,
    /// Recorded as the writer of every recording and record.
    pub software: String,
}

impl Synthesis<'_> {
    /// Simulates one sequence into its recording: the spec's solver settings first, then its
    /// retry settings while the gates fail; the recording is the last finished attempt's.
    /// Returns its record (not yet written). A sequence of an unusable garment is recorded
    /// as failed with why; a garment the run knows nothing of is an error.
    pub fn sequence(&self, p: &PlannedSequence) -> Result<ManifestRecord> {
        let spec = self.spec;
        if let Some(why) = self.unusable.get(&p.garment) {
            let solver = self
                .config(p, spec.solver.substeps, spec.solver.max_iterations)
                .solver;
            let gates = GateResult::unfinished(format!("could not set up: {why}"), false, true);
            return Ok(self.record(
                p,
                vec![Attempt {
                    solver,
                    gates,
                    wall_s: 0.0,
                }],
                0,
                0,
                0.0,
            ));
        }
        let (garment, attachments) =
            self.templates
                .get(&p.garment)
                .ok_or_else(|| sim::Error::Garment {
                    garment: p.garment.clone(),
                    problem: format!(
                        "sequence {} names a garment the run has no template of",
                        p.id
                    ),
                })?;
        let file = DatasetDir::sequence_file(&p.id);
        let path = self.dir.root.join(&file);
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
            let config = self.config(p, substeps, iterations);
            let solver = config.solver;
            let attempt_started = Instant::now();
            let prepared = config.validated().and_then(|config| {
                Prepared::with_motion_of(
                    self.model.clone(),
                    garment.clone(),
                    attachments.clone(),
                    config,
                )
            });
            let gates = match prepared {
                Err(e) => GateResult::unfinished(format!("could not set up: {e}"), false, true),
                Ok(prepared) => {
                    frames = prepared.scene.num_frames();
                    let deadline = attempt_started + Duration::from_secs_f64(spec.gates.timeout_s);
                    self.attempt(&prepared, &path, deadline)
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
        let mut record = self.record(
            p,
            attempts,
            frames,
            garment.positions.len(),
            started.elapsed().as_secs_f64(),
        );
        if path.exists() {
            let (sha, bytes) = files::sha256_file(&path)?;
            (record.file, record.sha256, record.bytes) = (Some(file), Some(sha), bytes);
        }
        Ok(record)
    }

    /// One attempt at a prepared sequence, recorded into `path` before `deadline`, judged by
    /// the spec's gates (a time-out or a solver failure is an unfinished attempt, its cause
    /// kept: a blow-up to non-finite values is not a finite one).
    fn attempt(&self, prepared: &Prepared, path: &Path, deadline: Instant) -> GateResult {
        let gates = &self.spec.gates;
        match prepared.record_file(path, &self.software, Some(deadline), |_| Ok(())) {
            Ok(summary) => GateResult::judge(&summary, gates),
            Err(sim::Error::Deadline { .. }) => {
                GateResult::unfinished(format!("time-out after {} s", gates.timeout_s), true, true)
            }
            Err(e) => {
                let finite = !matches!(
                    e,
                    sim::Error::BlowUp {
                        reason: BlowUpCause::NonFinite,
                        ..
                    }
                );
                GateResult::unfinished(format!("solver: {e}"), false, finite)
            }
        }
    }

    /// The record of a planned sequence after `attempts` (no recording yet).
    fn record(
        &self,
        p: &PlannedSequence,
        attempts: Vec<Attempt>,
        frames: usize,
        vertices: usize,
        wall_s: f64,
    ) -> ManifestRecord {
        let last = attempts.last().expect("at least one attempt");
        let ok = last.gates.passed;
        ManifestRecord {
            frames,
            vertices,
            status: if ok { Status::Ok } else { Status::Failed },
            reason: (!ok).then(|| last.gates.failed.join("; ")),
            attempts,
            wall_s,
            ..ManifestRecord::of_plan(p, &self.software)
        }
    }

    /// The scene configuration of a planned sequence with these solver settings: the spec's
    /// per-sequence keys (the same names, docs/DATASETS.md), recorded in its metadata.
    fn config(&self, p: &PlannedSequence, substeps: usize, iterations: usize) -> SceneConfig {
        let (spec, solver) = (self.spec, &self.spec.solver);
        SceneConfig {
            garment: p.garment.clone(),
            motion: p.motion.clone(),
            model: self.model_file.clone(),
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
                self_contact: solver.self_contact,
                self_contact_distance: solver.self_contact_distance,
                self_friction: solver.self_friction,
                acceleration: solver.acceleration,
                max_penetration_jump: solver.max_penetration_jump,
                ..SolverParams::default()
            },
            record: sim::config::RecordConfig::default(),
        }
    }
}

impl DatasetDir {
    /// Refuses a folder that holds another spec's dataset.
    pub fn check_spec(&self, spec: &DatasetSpec) -> Result<()> {
        let path = self.spec();
        if path.exists() && &DatasetSpec::load(&path)? != spec {
            return Err(Error::Dataset {
                path: self.root.display().to_string(),
                message: "holds a dataset of a different spec (its spec.toml differs); use another folder".into(),
            });
        }
        Ok(())
    }

    /// Stores the spec in the folder unless it is there (check it with
    /// [`Self::check_spec`] first).
    pub fn store_spec(&self, spec: &DatasetSpec) -> Result<()> {
        let path = self.spec();
        if !path.exists() {
            files::write_atomic(&path, spec.to_toml().as_bytes())?;
        }
        Ok(())
    }

    /// Removes what killed runs left: temporary files of the sequences `ids`. Returns how
    /// many.
    pub fn remove_leftovers(&self, ids: &[&str]) -> Result<usize> {
        let mut removed = 0;
        for folder in ["sequences", "records"] {
            let Ok(entries) = std::fs::read_dir(self.root.join(folder)) else {
                continue;
            };
            for entry in entries.flatten() {
                let name = entry.file_name().to_string_lossy().into_owned();
                let ours = ids.iter().any(|id| {
                    name.starts_with(&format!("{id}.mcap."))
                        || name.starts_with(&format!("{id}.json."))
                });
                if name.ends_with(".tmp") && ours {
                    std::fs::remove_file(entry.path()).map_err(|e| Error::Dataset {
                        path: entry.path().display().to_string(),
                        message: format!("cannot remove a leftover temporary file: {e}"),
                    })?;
                    removed += 1;
                }
            }
        }
        Ok(removed)
    }

    /// Writes the manifest when every planned sequence has a record (from `known`, this
    /// run's, else from the folder); returns how many are missing (0: written).
    pub fn write_manifest(
        &self,
        planned: &[PlannedSequence],
        known: &HashMap<String, ManifestRecord>,
    ) -> Result<usize> {
        let mut records = Vec::with_capacity(planned.len());
        let mut missing = 0;
        for p in planned {
            match known
                .get(&p.id)
                .cloned()
                .or_else(|| finished_record(self, &p.id))
            {
                Some(r) => records.push(r),
                None => missing += 1,
            }
        }
        if missing == 0 {
            files::write_json_lines(&self.manifest(), &records)?;
        }
        Ok(missing)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::{expand_motions, plan};

    const SPEC: &str = r#"
name = "synth-unit"
seed = 3
[sequence]
frames = 6
blend_frames = 2
settle_frames = 1
shapes_per_motion = 1
draws_per_shape = 1
[solver]
substeps = 1
max_iterations = 4
[gates]
retries = 1
retry_substeps = 2
retry_iterations = 4
[[garments]]
name = "skirt"
split = "train"
[[motions]]
source = "walk"
split = "train"
"#;

    /// A coarse skirt template (24 x 8) on the default body.
    fn run<'a>(spec: &'a DatasetSpec, dir: &'a DatasetDir) -> Synthesis<'a> {
        let model = BodyModel::default_body();
        let (garment, attachments) = sim::scene::builtin_template(
            &model,
            "skirt",
            &garments::SkirtParams {
                columns: 24,
                rings: 8,
                ..garments::SkirtParams::default()
            },
        )
        .unwrap();
        Synthesis {
            spec,
            dir,
            model: Arc::new(model),
            model_file: None,
            templates: HashMap::from([("skirt".into(), (Arc::new(garment), attachments))]),
            unusable: HashMap::new(),
            software: "test".into(),
        }
    }

    /// A sequence that passes records one attempt and the recording's checksum; one whose
    /// gates cannot pass is tried with the retry settings too and records why it failed,
    /// keeping the last attempt's recording; the manifest waits for every record.
    #[test]
    fn a_sequence_records_its_attempts_and_the_manifest_waits_for_all() {
        let folder = tempfile::tempdir().unwrap();
        let dir = DatasetDir::new(folder.path());
        let mut spec = DatasetSpec::parse(SPEC, std::path::Path::new("unit.toml")).unwrap();
        let planned = plan(&spec, &expand_motions(&spec).unwrap()).unwrap();
        let p = &planned[0];
        let record = run(&spec, &dir).sequence(p).unwrap();
        assert!(record.ok(), "{:?}", record.reason);
        assert_eq!((record.attempts.len(), record.frames), (1, 6));
        let (sha, _) = files::sha256_file(&dir.root.join(record.file.as_ref().unwrap())).unwrap();
        assert_eq!(record.sha256.as_deref(), Some(sha.as_str()));

        spec.gates.max_edge_stretch = 0.5; // no cloth is shorter than half its rest length
        let failed = run(&spec, &dir).sequence(p).unwrap();
        assert!(!failed.ok());
        assert_eq!(failed.attempts.len(), 2);
        assert_eq!(failed.attempts[1].solver.substeps, 2);
        assert!(
            failed.reason.as_deref().unwrap().contains("stretch"),
            "{failed:?}"
        );
        assert!(
            failed.file.is_some(),
            "the last attempt's recording is kept"
        );

        let mut unusable = run(&spec, &dir);
        unusable.templates.clear();
        unusable
            .unusable
            .insert("skirt".into(), "the template failed its gates".into());
        let skipped = unusable.sequence(p).unwrap();
        assert!(!skipped.ok() && skipped.file.is_none() && skipped.attempts.len() == 1);
        assert!(skipped.reason.unwrap().contains("failed its gates"));
        unusable.unusable.clear();
        assert!(
            unusable.sequence(p).is_err(),
            "a garment the run does not know"
        );

        let mut known = HashMap::new();
        let extra = PlannedSequence {
            id: "train-other".into(),
            ..p.clone()
        };
        let both = [p.clone(), extra];
        known.insert(p.id.clone(), record);
        assert_eq!(dir.write_manifest(&both, &known).unwrap(), 1);
        assert!(!dir.manifest().exists());
        assert_eq!(dir.write_manifest(&both[..1], &known).unwrap(), 0);
        assert!(dir.manifest().exists());
    }

    /// The built-in skirt is made without a notice (it is not cached); an unknown garment
    /// stops the run, naming it.
    #[test]
    fn templates_are_made_once_per_garment_and_unknown_ones_refused() {
        let spec = DatasetSpec::parse(SPEC, std::path::Path::new("unit.toml")).unwrap();
        let planned = plan(&spec, &expand_motions(&spec).unwrap()).unwrap();
        let cache = tempfile::tempdir().unwrap();
        let model = BodyModel::default_body();
        let told = std::sync::Mutex::new(Vec::new());
        let making = |name: &str, _: &Path| told.lock().unwrap().push(name.to_string());
        let both: Vec<&PlannedSequence> = vec![&planned[0], &planned[0]];
        let (made, unusable) = make_templates(&both, &model, cache.path(), &making).unwrap();
        assert_eq!(made.keys().collect::<Vec<_>>(), ["skirt"]);
        assert!(unusable.is_empty() && told.lock().unwrap().is_empty());
        let unknown = PlannedSequence {
            garment: "no_such_design".into(),
            ..planned[0].clone()
        };
        let e = make_templates(&[&unknown], &model, cache.path(), &making).unwrap_err();
        assert!(e.to_string().contains("no_such_design"), "{e}");
    }

    /// A folder keeps its spec: the same spec passes, another is refused; leftovers of the
    /// run's own sequences are removed, others' are not.
    #[test]
    fn a_folder_keeps_its_spec_and_loses_only_its_own_leftovers() {
        let folder = tempfile::tempdir().unwrap();
        let dir = DatasetDir::new(folder.path());
        let spec = DatasetSpec::parse(SPEC, std::path::Path::new("unit.toml")).unwrap();
        dir.check_spec(&spec).unwrap();
        dir.store_spec(&spec).unwrap();
        dir.check_spec(&spec).unwrap();
        let mut other = spec.clone();
        other.seed = 4;
        let e = dir.check_spec(&other).unwrap_err();
        assert!(matches!(&e, Error::Dataset { message, .. } if message.contains("different spec")));
        let sequences = folder.path().join("sequences");
        std::fs::create_dir_all(&sequences).unwrap();
        for name in ["a.mcap.1.tmp", "b.mcap.1.tmp", "a.mcap"] {
            std::fs::write(sequences.join(name), b"x").unwrap();
        }
        assert_eq!(dir.remove_leftovers(&["a"]).unwrap(), 1);
        assert!(!sequences.join("a.mcap.1.tmp").exists());
        assert!(sequences.join("b.mcap.1.tmp").exists() && sequences.join("a.mcap").exists());
    }
}
