//! Dataset verification: every record against its plan entry, its recording (checksum,
//! size, frames, seed, shape) and the gates, and the folder against its manifest.

use std::collections::{HashMap, HashSet};
use std::path::Path;

use super::{Attempt, DatasetDir, DatasetSpec, ManifestRecord, PlannedSequence};
use crate::error::{Error, Result};
use sim::recording::Recording;

/// What verifying a dataset found.
#[derive(Debug, Clone, PartialEq, serde::Serialize)]
pub struct Verification {
    /// Sequences in the manifest.
    pub sequences: usize,
    /// Sequences in the plan.
    pub planned: usize,
    /// Sequences that passed their gates.
    pub passed: usize,
    /// Every problem, each naming the sequence or file.
    pub problems: Vec<String>,
    /// Whether there is none.
    pub ok: bool,
}

/// The counts and the first 50 problems, as `dataset verify` prints them.
impl std::fmt::Display for Verification {
    fn fmt(&self, f: &mut std::fmt::Formatter) -> std::fmt::Result {
        let (sequences, planned, passed) = (self.sequences, self.planned, self.passed);
        let failed = sequences - passed;
        write!(
            f,
            "{sequences} sequences in the manifest ({planned} planned), {passed} passed their \
             gates, {failed} failed (recorded with reasons)"
        )?;
        for p in self.problems.iter().take(50) {
            write!(f, "\n  problem: {p}")?;
        }
        Ok(())
    }
}

/// The spec, plan and manifest of a dataset folder (an error if the manifest is missing: the
/// run is unfinished or its shards are not merged).
pub fn load(dir: &DatasetDir) -> Result<(DatasetSpec, Vec<PlannedSequence>, Vec<ManifestRecord>)> {
    let spec = DatasetSpec::load(&dir.spec())?;
    let planned: Vec<PlannedSequence> = files::read_json_lines(&dir.plan(), "dataset plan")?;
    if !dir.manifest().exists() {
        return Err(Error::Dataset {
            path: dir.root.display().to_string(),
            message: "has no manifest.jsonl: the run is unfinished, or its shards are not merged (`dataset merge`)".into(),
        });
    }
    let records: Vec<ManifestRecord> = files::read_json_lines(&dir.manifest(), "dataset manifest")?;
    Ok((spec, planned, records))
}

/// Verifies the dataset in `root`: records against the plan, recordings and gates, and no
/// file in `sequences/` that the manifest does not list.
pub fn verify(root: &Path) -> Result<Verification> {
    let dir = DatasetDir::new(root);
    let (spec, planned, records) = load(&dir)?;
    let by_id: HashMap<&str, &PlannedSequence> =
        planned.iter().map(|p| (p.id.as_str(), p)).collect();
    let mut problems = Vec::new();
    let mut seen = HashSet::new();
    for r in &records {
        if !seen.insert(r.sequence.id.as_str()) {
            problems.push(format!("{}: listed twice in the manifest", r.sequence.id));
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
        problems.extend(check_record(
            &dir,
            &spec,
            by_id.get(r.sequence.id.as_str()),
            r,
        ));
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
    let passed = records.iter().filter(|r| r.ok()).count();
    Ok(Verification {
        sequences: records.len(),
        planned: planned.len(),
        passed,
        ok: problems.is_empty(),
        problems,
    })
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
    let mut problem = |m: String| problems.push(format!("{}: {m}", r.sequence.id));
    let Some(p) = plan else {
        problem("not in the plan".into());
        return problems;
    };
    if (
        &p.split, &p.garment, &p.motion, p.seed, &p.betas, p.material,
    ) != (
        &r.sequence.split,
        &r.sequence.garment,
        &r.sequence.motion,
        r.sequence.seed,
        &r.sequence.betas,
        r.sequence.material,
    ) {
        problem("split, garment, motion, seed, shape or material differ from the plan".into());
    }
    let Some(last) = r.attempts.last() else {
        problem("no attempts recorded".into());
        return problems;
    };
    if r.ok() != last.gates.passed {
        problem(format!(
            "status '{}' disagrees with the last attempt's gates",
            r.status
        ));
    }
    if r.ok() && r.file.is_none() {
        problem("passed but has no recording".into());
    }
    if let Err(e) = r.check_paths() {
        problem(e.to_string());
        return problems;
    }
    let Some(file) = &r.file else {
        return problems;
    };
    for found in check_recording(&dir.root.join(file), file, spec, r, last) {
        problem(found);
    }
    problems
}

/// The recording `file` (at `path`) against its record `r` and the last attempt: checksum and
/// size, frames, vertices, seed and shape, its statistics against the attempt's gate values
/// and, where it passed, the spec's gates. The problems found, without the sequence's id.
fn check_recording(
    path: &Path,
    file: &str,
    spec: &DatasetSpec,
    r: &ManifestRecord,
    last: &Attempt,
) -> Vec<String> {
    let mut problems = Vec::new();
    match files::sha256_file(path) {
        Err(e) => return vec![format!("recording {file} is unreadable: {e:#}")],
        Ok((sha, bytes)) => {
            if Some(&sha) != r.sha256.as_ref() || bytes != r.bytes {
                problems.push(format!(
                    "recording {file} does not match its checksum or size"
                ));
            }
        }
    }
    let recording = match Recording::read(path) {
        Ok(rec) => rec,
        Err(e) => {
            problems.push(format!("{e}"));
            return problems;
        }
    };
    let meta = recording.meta.as_ref().expect("checked by the reader");
    if recording.garment.len() != r.frames || meta.frames != r.frames {
        problems.push(format!(
            "recording has {} frames, the record {}",
            recording.garment.len(),
            r.frames
        ));
    }
    if recording.template.positions.len() != r.vertices {
        problems.push("vertex count differs from the record".into());
    }
    if meta.seed != Some(r.sequence.seed) || meta.betas != r.sequence.betas {
        problems.push("recording's seed or shape differs from the record".into());
    }
    let (pen, inside, stretch, crossings) = recorded_extremes(&recording);
    let g = &last.gates;
    if !last.gates.timed_out
        && ((pen - g.max_penetration_m).abs() > 1e-9
            || inside != g.max_verts_inside
            || (stretch - g.max_edge_stretch).abs() > 1e-9
            || crossings != g.max_self_intersections)
    {
        problems.push("gate values differ from the recording's statistics".into());
    }
    if r.ok() {
        let gates = &spec.gates;
        let allowed = (gates.max_inside_fraction * r.vertices as f64).floor() as usize;
        if pen > gates.max_penetration_m
            || inside > allowed
            || stretch > gates.max_edge_stretch
            || crossings > gates.max_self_intersections
        {
            problems.push("marked ok but its statistics break the spec's gates".into());
        }
    }
    problems
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::{expand_motions, finished_record, plan};

    /// A record of `p` that failed without a recording.
    fn failed(p: &PlannedSequence) -> ManifestRecord {
        ManifestRecord {
            reason: Some("a test".into()),
            ..ManifestRecord::of_plan(p, "test")
        }
    }

    #[test]
    fn a_dataset_folder_is_checked_against_its_plan_manifest_and_files() {
        let root = tempfile::tempdir().unwrap();
        let dir = DatasetDir::new(root.path());
        let text = include_str!("../../specs/tiny.toml");
        std::fs::write(dir.spec(), text).unwrap();
        let spec = DatasetSpec::parse(text, &dir.spec()).unwrap();
        let planned = plan(&spec, &expand_motions(&spec).unwrap()).unwrap();
        files::write_json_lines(&dir.plan(), &planned).unwrap();
        // No manifest yet: an unfinished run, named as such.
        let unfinished = verify(root.path()).unwrap_err().to_string();
        assert!(unfinished.contains("has no manifest.jsonl"), "{unfinished}");
        let mut stranger = failed(&planned[0]);
        stranger.sequence.id = "not-planned".into();
        let records = [failed(&planned[0]), failed(&planned[0]), stranger];
        files::write_json_lines(&dir.manifest(), &records).unwrap();
        std::fs::create_dir(root.path().join("sequences")).unwrap();
        std::fs::write(root.path().join("sequences/stray.mcap"), b"").unwrap();
        let found = verify(root.path()).unwrap();
        assert_eq!((found.sequences, found.planned), (3, planned.len()));
        assert_eq!(found.passed, 0);
        let problems = found.problems.join("\n");
        let missing = format!(
            "{} planned sequences are not in the manifest",
            planned.len() - 1
        );
        for expected in [
            "listed twice in the manifest",
            &missing,
            "not-planned: not in the plan",
            "no attempts recorded",
            "sequences/stray.mcap: a file the manifest does not list",
        ] {
            assert!(
                problems.contains(expected),
                "{expected} missing from:\n{problems}"
            );
        }
    }

    #[test]
    fn a_record_counts_as_finished_only_with_its_recording_intact() {
        let root = tempfile::tempdir().unwrap();
        let dir = DatasetDir::new(root.path());
        let text = include_str!("../../specs/tiny.toml");
        let spec = DatasetSpec::parse(text, &dir.spec()).unwrap();
        let p = &plan(&spec, &expand_motions(&spec).unwrap()).unwrap()[0];
        assert!(finished_record(&dir, &p.id).is_none(), "no record yet");
        let file = DatasetDir::sequence_file(&p.id);
        std::fs::create_dir_all(root.path().join("sequences")).unwrap();
        std::fs::write(root.path().join(&file), b"recorded").unwrap();
        let mut record = failed(p);
        record.file = Some(file.clone());
        record.sha256 = Some(files::sha256_hex(b"recorded"));
        std::fs::create_dir_all(root.path().join("records")).unwrap();
        let write = |r: &ManifestRecord| {
            std::fs::write(dir.record(&p.id), serde_json::to_vec(r).unwrap()).unwrap()
        };
        write(&record);
        assert_eq!(finished_record(&dir, &p.id), Some(record.clone()));
        std::fs::write(root.path().join(&file), b"damaged").unwrap();
        assert!(finished_record(&dir, &p.id).is_none(), "damaged recording");
        record.file = Some("sequences/another.mcap".into());
        write(&record);
        assert!(finished_record(&dir, &p.id).is_none(), "wrong file name");
    }
}
