//! Writing outputs safely: every file goes to a temporary name beside its destination and is
//! renamed into place only when complete, so an interrupted run leaves nothing half-written.

use std::fs::File;
use std::io::{BufWriter, Write};
use std::path::Path;

use anyhow::{Context, Result};
use serde::Serialize;

/// Writes `path` through `fill`, atomically ([`files::write_fallible`]; parent folders
/// created).
pub fn write_atomic(
    path: &Path,
    fill: impl FnOnce(&mut BufWriter<File>) -> Result<()>,
) -> Result<()> {
    if let Some(dir) = path.parent().filter(|d| !d.as_os_str().is_empty()) {
        std::fs::create_dir_all(dir)
            .with_context(|| format!("cannot create folder {}", dir.display()))?;
    }
    files::write_fallible(path, fill).with_context(|| format!("writing {}", path.display()))
}

/// Writes a value as pretty JSON, atomically.
pub fn write_json<T: Serialize>(path: &Path, value: &T) -> Result<()> {
    write_atomic(path, |w| {
        serde_json::to_writer_pretty(&mut *w, value)?;
        writeln!(w)?;
        Ok(())
    })
}

/// Writes a triangle mesh as OBJ (vertices in the given order, 1-based faces), atomically.
pub fn write_obj(
    path: &Path,
    vertices: &[[f64; 3]],
    faces: &[[u32; 3]],
    comment: &str,
) -> Result<()> {
    write_atomic(path, |w| {
        Ok(garments::write_mesh_obj(w, comment, vertices, faces)?)
    })
}
