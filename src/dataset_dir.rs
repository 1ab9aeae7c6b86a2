//! A dataset folder as `synth` and `dataset` share it: its paths, checksums, JSON Lines files
//! and the finished-sequence check that makes a re-run resume.
//!
//! Layout: `spec.toml` (the spec), `plan.jsonl` (every planned sequence),
//! `templates/<garment>.obj`, `sequences/<id>.mcap`, `records/<id>.json` (one manifest line
//! per finished sequence, written after its recording) and `manifest.jsonl` (the records in
//! plan order, written when every sequence has one).

use std::io::{Read, Write};
use std::path::{Path, PathBuf};

use anyhow::{Context, Result};
use sha2::{Digest, Sha256};
use sim::dataset::ManifestRecord;

use crate::output::write_atomic;

/// Paths inside a dataset folder.
pub struct DatasetDir {
    pub root: PathBuf,
}

impl DatasetDir {
    pub fn new(root: &Path) -> Self {
        Self {
            root: root.to_path_buf(),
        }
    }
    pub fn spec(&self) -> PathBuf {
        self.root.join("spec.toml")
    }
    pub fn plan(&self) -> PathBuf {
        self.root.join("plan.jsonl")
    }
    pub fn manifest(&self) -> PathBuf {
        self.root.join("manifest.jsonl")
    }
    pub fn sequence_file(id: &str) -> String {
        format!("sequences/{id}.mcap")
    }
    pub fn record(&self, id: &str) -> PathBuf {
        self.root.join("records").join(format!("{id}.json"))
    }
    pub fn template(&self, garment: &str) -> PathBuf {
        let name: String = Path::new(garment)
            .file_stem()
            .map_or(garment.into(), |s| s.to_string_lossy().into_owned());
        self.root.join("templates").join(format!("{name}.obj"))
    }
}

/// SHA-256 of a file, hex.
pub fn sha256_file(path: &Path) -> Result<(String, u64)> {
    let (file, len) = files::open(path)?;
    // Never more than the size it had when opened (a growing file still ends).
    let mut file = file.take(len);
    let mut hasher = Sha256::new();
    let mut buffer = vec![0u8; 1 << 20];
    let mut bytes = 0u64;
    loop {
        let n = file.read(&mut buffer)?;
        if n == 0 {
            break;
        }
        hasher.update(&buffer[..n]);
        bytes += n as u64;
    }
    let hex = hasher
        .finalize()
        .iter()
        .map(|b| format!("{b:02x}"))
        .collect();
    Ok((hex, bytes))
}

/// Reads a JSON Lines file of `T`, naming the file and line of a bad one.
pub fn read_jsonl<T: serde::de::DeserializeOwned>(path: &Path) -> Result<Vec<T>> {
    let text = files::read_to_string(path, files::limits::LINES, "JSON Lines file")?;
    text.lines()
        .enumerate()
        .filter(|(_, l)| !l.trim().is_empty())
        .map(|(i, l)| {
            serde_json::from_str(l)
                .with_context(|| format!("{} line {}: not a valid entry", path.display(), i + 1))
        })
        .collect()
}

/// Writes values as JSON Lines, atomically.
pub fn write_jsonl<T: serde::Serialize>(path: &Path, values: &[T]) -> Result<()> {
    write_atomic(path, |w| {
        for v in values {
            serde_json::to_writer(&mut *w, v)?;
            writeln!(w)?;
        }
        Ok(())
    })
}

/// A finished sequence's record, if it is complete: the record parses and its recording (if
/// any) matches the checksum.
pub fn finished_record(dir: &DatasetDir, id: &str) -> Option<ManifestRecord> {
    let text = files::read_to_string(&dir.record(id), files::limits::TEXT, "record").ok()?;
    let record: ManifestRecord = serde_json::from_str(&text).ok()?;
    record.check_paths().ok()?;
    if let (Some(file), Some(sha)) = (&record.file, &record.sha256) {
        let (actual, _) = sha256_file(&dir.root.join(file)).ok()?;
        if &actual != sha {
            return None;
        }
    }
    Some(record)
}
