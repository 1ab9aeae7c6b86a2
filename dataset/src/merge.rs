//! Shards of one dataset (folders synthesized from the same spec, each with some of the
//! plan's sequences finished) merged into one folder with the whole manifest.

use std::path::{Path, PathBuf};

use super::{DatasetDir, DatasetSpec, ManifestRecord, PlannedSequence, finished_record};
use crate::error::{Error, Result};

/// Merges the shard folders `roots` into `out` (which may be one of them): every planned
/// sequence's finished record is found first (else nothing is written), then the spec, the
/// plan, the recordings, templates and records are copied (atomically; a file already in
/// place is left) and the manifest is written. Returns the sequences merged.
pub fn merge(out: &Path, roots: &[PathBuf]) -> Result<usize> {
    let fail = |path: &Path, message: String| Error::Dataset {
        path: path.display().to_string(),
        message,
    };
    let first = roots
        .first()
        .ok_or_else(|| fail(out, "no shard folders to merge".into()))?;
    let dirs: Vec<DatasetDir> = roots.iter().map(|r| DatasetDir::new(r)).collect();
    let spec = DatasetSpec::load(&dirs[0].spec())?;
    for d in &dirs[1..] {
        if DatasetSpec::load(&d.spec())? != spec {
            let message = format!(
                "holds another spec than {}: they are not shards of one dataset",
                first.display()
            );
            return Err(fail(&d.root, message));
        }
    }
    let planned: Vec<PlannedSequence> = files::read_json_lines(&dirs[0].plan(), "dataset plan")?;
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
    if let Some(id) = missing.first() {
        let message = format!(
            "{} of {} planned sequences have no finished record in the shards (first: {id}); finish those shards first",
            missing.len(),
            planned.len()
        );
        return Err(fail(first, message));
    }
    let target = DatasetDir::new(out);
    std::fs::create_dir_all(out).map_err(|e| fail(out, format!("cannot create it: {e}")))?;
    copy_into(&dirs[0].spec(), &target.spec())?;
    copy_into(&dirs[0].plan(), &target.plan())?;
    let mut records: Vec<ManifestRecord> = Vec::with_capacity(found.len());
    for (d, r) in found {
        r.check_paths()
            .map_err(|e| fail(&d.manifest(), e.to_string()))?;
        if let Some(file) = &r.file {
            copy_into(&d.root.join(file), &target.root.join(file))?;
        }
        let template = d.template(&r.sequence.garment);
        if template.exists() {
            copy_into(&template, &target.template(&r.sequence.garment))?;
        }
        copy_into(&d.record(&r.sequence.id), &target.record(&r.sequence.id))?;
        records.push(r);
    }
    files::write_json_lines(&target.manifest(), &records)?;
    Ok(records.len())
}

/// Copies `from` to `to` atomically (its folder made if missing) unless they are the same
/// file.
fn copy_into(from: &Path, to: &Path) -> Result<()> {
    let io = |path: &Path, source| files::Error::Io {
        path: path.to_path_buf(),
        source,
    };
    let same = |a: &Path, b: &Path| -> Result<bool> {
        let canonical = |p: &Path| std::fs::canonicalize(p).map_err(|e| io(p, e));
        Ok(a == b || (b.exists() && canonical(a)? == canonical(b)?))
    };
    if same(from, to)? {
        return Ok(());
    }
    if let Some(dir) = to.parent() {
        std::fs::create_dir_all(dir).map_err(|e| io(dir, e))?;
    }
    let (mut file, len) = files::open(from)?;
    files::write_with(to, |w| {
        use std::io::Read;
        std::io::copy(&mut (&mut file).take(len), w).map(|_| ())
    })?;
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::{expand_motions, plan};

    const SPEC: &str = r#"
name = "merge-unit"
seed = 3
[sequence]
frames = 6
shapes_per_motion = 2
draws_per_shape = 1
[[garments]]
name = "skirt"
split = "train"
[[motions]]
source = "walk"
split = "train"
"#;

    /// A shard folder with the spec, the plan and records (no recordings) of `ids`.
    fn shard(root: &Path, spec: &DatasetSpec, planned: &[PlannedSequence], ids: &[usize]) {
        let dir = DatasetDir::new(root);
        std::fs::create_dir_all(root.join("records")).unwrap();
        dir.store_spec(spec).unwrap();
        files::write_json_lines(&dir.plan(), planned).unwrap();
        for &i in ids {
            let p = &planned[i];
            let record = serde_json::json!({
                "id": p.id, "split": p.split, "garment": p.garment, "motion": p.motion,
                "betas": p.betas, "material": p.material, "friction": p.friction, "seed": p.seed,
                "frames": 6, "vertices": 4, "status": "ok", "attempts": [], "bytes": 0,
                "software": "test", "wall_s": 0.0
            });
            std::fs::write(dir.record(&p.id), record.to_string()).unwrap();
        }
    }

    #[test]
    fn shards_merge_only_when_every_sequence_is_finished() {
        let folder = tempfile::tempdir().unwrap();
        let spec = DatasetSpec::parse(SPEC, Path::new("unit.toml")).unwrap();
        let planned = plan(&spec, &expand_motions(&spec).unwrap()).unwrap();
        assert_eq!(planned.len(), 2);
        let (a, b, out) = (
            folder.path().join("a"),
            folder.path().join("b"),
            folder.path().join("out"),
        );
        shard(&a, &spec, &planned, &[0]);
        let e = merge(&out, std::slice::from_ref(&a)).unwrap_err();
        assert!(
            matches!(&e, Error::Dataset { message, .. } if message.contains("1 of 2 planned sequences")),
            "{e}"
        );
        assert!(
            !out.exists(),
            "nothing is written before every record is found"
        );
        shard(&b, &spec, &planned, &[1]);
        assert_eq!(merge(&out, &[a.clone(), b.clone()]).unwrap(), 2);
        let merged: Vec<ManifestRecord> =
            files::read_json_lines(&DatasetDir::new(&out).manifest(), "manifest").unwrap();
        let ids: Vec<&str> = merged.iter().map(|r| r.sequence.id.as_str()).collect();
        assert_eq!(ids, [planned[0].id.as_str(), planned[1].id.as_str()]);
        // Into one of the shards, and refused for another spec.
        assert_eq!(merge(&a, &[a.clone(), b.clone()]).unwrap(), 2);
        let mut other = spec.clone();
        other.seed = 4;
        std::fs::write(DatasetDir::new(&b).spec(), other.to_toml()).unwrap();
        let e = merge(&out, &[a, b]).unwrap_err();
        assert!(
            matches!(&e, Error::Dataset { message, .. } if message.contains("not shards of one dataset")),
            "{e}"
        );
    }
}
