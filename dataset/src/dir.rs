//! A dataset folder: where its files lie, and the finished-sequence check that makes a
//! re-run resume.
//!
//! Layout: `spec.toml` (the spec), `plan.jsonl` (every planned sequence),
//! `templates/<garment>.obj`, `sequences/<id>.mcap`, `records/<id>.json` (one manifest line
//! per finished sequence, written after its recording) and `manifest.jsonl` (the records in
//! plan order, written when every sequence has one).

use std::collections::HashMap;
use std::path::{Path, PathBuf};

use super::{ManifestRecord, PlannedSequence};

/// Paths inside a dataset folder.
pub struct DatasetDir {
    /// The folder.
    pub root: PathBuf,
}

impl DatasetDir {
    /// The dataset folder at `root`.
    pub fn new(root: &Path) -> Self {
        Self {
            root: root.to_path_buf(),
        }
    }
    /// `spec.toml`: the spec the dataset was made from.
    pub fn spec(&self) -> PathBuf {
        self.root.join("spec.toml")
    }
    /// `plan.jsonl`: every planned sequence.
    pub fn plan(&self) -> PathBuf {
        self.root.join("plan.jsonl")
    }
    /// `manifest.jsonl`: the records in plan order, once every sequence has one.
    pub fn manifest(&self) -> PathBuf {
        self.root.join("manifest.jsonl")
    }
    /// A sequence's recording, relative to the folder (as records name it).
    pub fn sequence_file(id: &str) -> String {
        format!("sequences/{id}.mcap")
    }
    /// A finished sequence's record.
    pub fn record(&self, id: &str) -> PathBuf {
        self.root.join("records").join(format!("{id}.json"))
    }
    /// The template OBJ a garment (library name or OBJ path) is simulated from.
    pub fn template(&self, garment: &str) -> PathBuf {
        let name: String = Path::new(garment)
            .file_stem()
            .map_or(garment.into(), |s| s.to_string_lossy().into_owned());
        self.root.join("templates").join(format!("{name}.obj"))
    }
}

/// The records of the sequences of `planned` that are finished ([`finished_record`]: each
/// checked against its checksum once), by id, and the sequences still to run, in order.
pub fn split_finished<'a>(
    dir: &DatasetDir,
    planned: &[&'a PlannedSequence],
) -> (HashMap<String, ManifestRecord>, Vec<&'a PlannedSequence>) {
    let mut finished = HashMap::new();
    let mut todo = Vec::new();
    for &p in planned {
        match finished_record(dir, &p.id) {
            Some(r) => {
                finished.insert(p.id.clone(), r);
            }
            None => todo.push(p),
        }
    }
    (finished, todo)
}

/// A finished sequence's record, if it is complete: the record parses and its recording (if
/// any) matches the checksum.
pub fn finished_record(dir: &DatasetDir, id: &str) -> Option<ManifestRecord> {
    let text = files::read_to_string(&dir.record(id), files::limits::TEXT, "record").ok()?;
    let record: ManifestRecord = serde_json::from_str(&text).ok()?;
    record.check_paths().ok()?;
    if let (Some(file), Some(sha)) = (&record.file, &record.sha256) {
        let (actual, _) = files::sha256_file(&dir.root.join(file)).ok()?;
        if &actual != sha {
            return None;
        }
    }
    Some(record)
}
