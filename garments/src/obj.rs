//! OBJ import and export with UVs (tobj reads; writing is a few lines of text).

use std::io::Write;
use std::path::Path;

use crate::error::{Error, Result};
use crate::mesh::Garment;

/// Reads an OBJ with `vt` coordinates (all objects merged, polygons triangulated).
pub fn read_obj(path: &Path) -> Result<Garment> {
    let name = path.display().to_string();
    let options = tobj::LoadOptions {
        single_index: false,
        triangulate: true,
        ignore_points: true,
        ignore_lines: true,
    };
    let (models, _) = tobj::load_obj(path, &options).map_err(|e| match e {
        tobj::LoadError::OpenFileFailed => Error::Io {
            path: name.clone(),
            source: std::io::Error::new(std::io::ErrorKind::NotFound, "cannot open file"),
        },
        other => Error::Format {
            path: name.clone(),
            message: format!("not a readable OBJ: {other}"),
        },
    })?;
    let mut g = Garment {
        name: path
            .file_stem()
            .map(|s| s.to_string_lossy().into_owned())
            .unwrap_or_default(),
        positions: Vec::new(),
        triangles: Vec::new(),
        uvs: Vec::new(),
        uv_triangles: Vec::new(),
    };
    for model in models {
        let m = model.mesh;
        if m.texcoords.is_empty() {
            return Err(Error::Format {
                path: name,
                message: format!(
                    "object '{}' has no UVs (vt lines); templates need them",
                    model.name
                ),
            });
        }
        let (p0, t0) = (g.positions.len() as u32, g.uvs.len() as u32);
        g.positions.extend(
            m.positions
                .chunks(3)
                .map(|c| [c[0] as f64, c[1] as f64, c[2] as f64]),
        );
        g.uvs
            .extend(m.texcoords.chunks(2).map(|c| [c[0] as f64, c[1] as f64]));
        g.triangles.extend(
            m.indices
                .chunks(3)
                .map(|c| [c[0] + p0, c[1] + p0, c[2] + p0]),
        );
        g.uv_triangles.extend(
            m.texcoord_indices
                .chunks(3)
                .map(|c| [c[0] + t0, c[1] + t0, c[2] + t0]),
        );
    }
    g.validate().map_err(|e| Error::Format {
        path: name,
        message: e.to_string(),
    })?;
    Ok(g)
}

/// Writes the garment as OBJ text (v, vt, f v/vt) to `out`.
pub fn write_obj<W: Write>(
    out: &mut W,
    garment: &Garment,
    positions: Option<&[[f64; 3]]>,
) -> std::io::Result<()> {
    writeln!(
        out,
        "# {} ({} vertices, {} triangles)",
        garment.name,
        garment.positions.len(),
        garment.triangles.len()
    )?;
    for p in positions.unwrap_or(&garment.positions) {
        writeln!(out, "v {:.6} {:.6} {:.6}", p[0], p[1], p[2])?;
    }
    for uv in &garment.uvs {
        writeln!(out, "vt {:.6} {:.6}", uv[0], uv[1])?;
    }
    for (t, uv) in garment.triangles.iter().zip(&garment.uv_triangles) {
        writeln!(
            out,
            "f {}/{} {}/{} {}/{}",
            t[0] + 1,
            uv[0] + 1,
            t[1] + 1,
            uv[1] + 1,
            t[2] + 1,
            uv[2] + 1
        )?;
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn round_trip_and_errors() {
        let g = crate::builtin::tube_for_tests();
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("tube.obj");
        let mut f = std::fs::File::create(&path).unwrap();
        write_obj(&mut f, &g, None).unwrap();
        drop(f);
        let back = read_obj(&path).unwrap();
        // tobj renumbers vertices in order of use: compare the triangles' corners.
        assert_eq!(back.triangles.len(), g.triangles.len());
        for t in 0..g.triangles.len() {
            for k in 0..3 {
                let (a, b) = (
                    back.positions[back.triangles[t][k] as usize],
                    g.positions[g.triangles[t][k] as usize],
                );
                assert!(
                    (0..3).all(|c| (a[c] - b[c]).abs() < 1e-5),
                    "triangle {t} corner {k}"
                );
                let (u, w) = (
                    back.uvs[back.uv_triangles[t][k] as usize],
                    g.uvs[g.uv_triangles[t][k] as usize],
                );
                assert!(
                    (0..2).all(|c| (u[c] - w[c]).abs() < 1e-5),
                    "triangle {t} UV corner {k}"
                );
            }
        }

        let bad = dir.path().join("no_uv.obj");
        std::fs::write(&bad, "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n").unwrap();
        let e = read_obj(&bad).unwrap_err().to_string();
        assert!(e.contains("no_uv.obj") && e.contains("no UVs"), "{e}");
        let missing = read_obj(&dir.path().join("missing.obj"))
            .unwrap_err()
            .to_string();
        assert!(missing.contains("missing.obj"), "{missing}");
    }
}
