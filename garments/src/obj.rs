//! OBJ import and export with UVs and groups, PLY export. tobj reads OBJ; writing either
//! format is a few lines of text, so no crate is used for it.
//!
//! Panels are OBJ groups (`g name`). tobj gives every group its own copy of the vertices it
//! uses, so vertices of different groups at exactly the same position are welded back into
//! one (a seam between panels); vertices within one group are kept as they are.

use std::collections::HashMap;
use std::io::Write;
use std::path::Path;

use crate::error::{Error, Result};
use crate::mesh::Garment;

/// Reads an OBJ: every group becomes a panel, polygons are triangulated. Only unreadable files
/// are refused here; [`crate::check`] reports what is wrong with the mesh itself (a file
/// without `vt` lines reads with no UVs, which the check reports).
pub fn read_obj(path: &Path) -> Result<Garment> {
    read_obj_numbered(path).map(|(garment, _)| garment)
}

/// [`read_obj`], with the 1-based number of each vertex's `v` line in the file (the first
/// line with its exact coordinates), so that errors name vertices as the user's file does:
/// tobj copies vertices per group in the order faces use them, and seams are welded here.
pub fn read_obj_numbered(path: &Path) -> Result<(Garment, Vec<u32>)> {
    let text = files::read(path, files::limits::MESH, "mesh")?;
    let stem = path
        .file_stem()
        .map(|s| s.to_string_lossy().into_owned())
        .unwrap_or_default();
    parse_obj(&text, &path.display().to_string(), &stem)
}

/// [`read_obj_numbered`] of OBJ text already in memory: `name` names it in errors, `stem`
/// names the garment and its ungrouped panel.
pub fn parse_obj(text: &[u8], name: &str, stem: &str) -> Result<(Garment, Vec<u32>)> {
    let name = name.to_string();
    let options = tobj::LoadOptions {
        single_index: false,
        triangulate: true,
        ignore_points: true,
        ignore_lines: true,
    };
    // A byte-order mark (some Windows editors write one) is not part of the first line.
    let text = text.strip_prefix(b"\xef\xbb\xbf").unwrap_or(text);
    check_face_indices(text, &name)?;
    // Materials are not used: a `mtllib` line reads nothing.
    let no_materials = |_: &Path| Err(tobj::LoadError::OpenFileFailed);
    let (models, _) =
        tobj::load_obj_buf(&mut &text[..], &options, no_materials).map_err(|e| Error::Format {
            path: name.clone(),
            message: format!("not a readable OBJ: {e}"),
        })?;
    if models.iter().all(|m| m.mesh.indices.is_empty()) {
        return Err(Error::Format {
            path: name,
            message: "no faces".into(),
        });
    }
    let stem = stem.to_string();
    let mut g = Garment {
        name: stem.clone(),
        ..Garment::default()
    };
    // Exact-position weld across groups.
    let mut welded: HashMap<[u64; 3], u32> = HashMap::new();
    for model in models {
        let m = model.mesh;
        if m.indices.is_empty() {
            continue;
        }
        let panel = if model.name.is_empty() || model.name == "unnamed_object" {
            stem.clone()
        } else {
            model.name.clone()
        };
        let panel_index = match g.panels.iter().position(|p| *p == panel) {
            Some(i) => i,
            None => {
                g.panels.push(panel);
                g.panels.len() - 1
            }
        } as u32;
        let local: Vec<u32> = m
            .positions
            .chunks(3)
            .map(|c| {
                let p = [c[0] as f64, c[1] as f64, c[2] as f64];
                let key = p.map(f64::to_bits);
                *welded.entry(key).or_insert_with(|| {
                    g.positions.push(p);
                    g.positions.len() as u32 - 1
                })
            })
            .collect();
        g.triangles.extend(
            m.indices
                .chunks(3)
                .map(|c| [c[0], c[1], c[2]].map(|i| local[i as usize])),
        );
        g.triangle_panels
            .extend(std::iter::repeat_n(panel_index, m.indices.len() / 3));
        if !m.texcoords.is_empty() && m.texcoord_indices.len() == m.indices.len() {
            let t0 = g.uvs.len() as u32;
            g.uvs
                .extend(m.texcoords.chunks(2).map(|c| [c[0] as f64, c[1] as f64]));
            g.uv_triangles.extend(
                m.texcoord_indices
                    .chunks(3)
                    .map(|c| [c[0] + t0, c[1] + t0, c[2] + t0]),
            );
        }
    }
    if g.uv_triangles.len() != g.triangles.len() {
        // Some group lacks UVs: the whole mesh is reported as having none.
        g.uvs.clear();
        g.uv_triangles.clear();
    }
    let numbers = vertex_numbers(text, &g.positions);
    Ok((g, numbers))
}

/// The 1-based `v` line number of each position (tobj reads coordinates as f32), or an empty
/// list if some position has no line (then errors fall back to internal indices).
fn vertex_numbers(text: &[u8], positions: &[[f64; 3]]) -> Vec<u32> {
    let mut first: HashMap<[u64; 3], u32> = HashMap::new();
    let lines = text
        .split(|&b| b == b'\n')
        .filter_map(|l| std::str::from_utf8(l).ok());
    let mut count = 0u32;
    for line in lines {
        let mut words = line.split_whitespace();
        if words.next() != Some("v") {
            continue;
        }
        count += 1;
        let c: Vec<f64> = words
            .take(3)
            .filter_map(|w| w.parse::<f32>().ok())
            .map(f64::from)
            .collect();
        if let [x, y, z] = c[..] {
            first.entry([x, y, z].map(f64::to_bits)).or_insert(count);
        }
    }
    positions
        .iter()
        .map(|p| first.get(&p.map(f64::to_bits)).copied())
        .collect::<Option<Vec<u32>>>()
        .unwrap_or_default()
}

/// Writes a plain triangle mesh as OBJ: `comment` as `#` lines, the vertices in order (6
/// decimals), 1-based faces. For meshes that are not garments (a posed body).
pub fn write_mesh_obj<W: Write>(
    out: &mut W,
    comment: &str,
    vertices: &[[f64; 3]],
    faces: &[[u32; 3]],
) -> std::io::Result<()> {
    for line in comment.lines() {
        writeln!(out, "# {line}")?;
    }
    for v in vertices {
        writeln!(out, "v {:.6} {:.6} {:.6}", v[0], v[1], v[2])?;
    }
    for f in faces {
        writeln!(out, "f {} {} {}", f[0] + 1, f[1] + 1, f[2] + 1)?;
    }
    Ok(())
}

/// Writes the garment as OBJ text (v, vt, one `g` group per panel, f v/vt) to `out`, at
/// `positions` when given (a simulated frame) or the template positions.
pub fn write_obj<W: Write>(
    out: &mut W,
    garment: &Garment,
    positions: Option<&[[f64; 3]]>,
) -> std::io::Result<()> {
    writeln!(
        out,
        "# {} ({} vertices, {} triangles, {} panels)",
        garment.name,
        garment.positions.len(),
        garment.triangles.len(),
        garment.panels.len()
    )?;
    for p in positions.unwrap_or(&garment.positions) {
        writeln!(out, "v {:.6} {:.6} {:.6}", p[0], p[1], p[2])?;
    }
    for uv in &garment.uvs {
        writeln!(out, "vt {:.6} {:.6}", uv[0], uv[1])?;
    }
    for (panel, panel_name) in garment.panels.iter().enumerate() {
        writeln!(out, "g {panel_name}")?;
        for ((t, uv), _) in garment
            .triangles
            .iter()
            .zip(&garment.uv_triangles)
            .zip(&garment.triangle_panels)
            .filter(|(_, p)| **p as usize == panel)
        {
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
    }
    Ok(())
}

/// Writes the garment as binary little-endian PLY: float vertices, and faces with their
/// per-corner UVs (`texcoord`, 6 floats) and panel index, the layout MeshLab and Blender read.
pub fn write_ply<W: Write>(out: &mut W, garment: &Garment) -> std::io::Result<()> {
    write!(
        out,
        "ply\nformat binary_little_endian 1.0\ncomment {} panels: {}\n\
         element vertex {}\nproperty float x\nproperty float y\nproperty float z\n\
         element face {}\nproperty list uchar int vertex_indices\n\
         property list uchar float texcoord\nproperty int panel\nend_header\n",
        garment.name,
        garment.panels.join(","),
        garment.positions.len(),
        garment.triangles.len()
    )?;
    for p in &garment.positions {
        for c in p {
            out.write_all(&(*c as f32).to_le_bytes())?;
        }
    }
    for (t, tri) in garment.triangles.iter().enumerate() {
        out.write_all(&[3u8])?;
        for v in tri {
            out.write_all(&(*v as i32).to_le_bytes())?;
        }
        out.write_all(&[6u8])?;
        let uv = garment.uv_triangles.get(t).copied().unwrap_or([0; 3]);
        for i in uv {
            let c = garment.uvs.get(i as usize).copied().unwrap_or([0.0; 2]);
            out.write_all(&(c[0] as f32).to_le_bytes())?;
            out.write_all(&(c[1] as f32).to_le_bytes())?;
        }
        let panel = garment.triangle_panels.get(t).copied().unwrap_or(0);
        out.write_all(&(panel as i32).to_le_bytes())?;
    }
    Ok(())
}

/// Refuses text that is not UTF-8 and face indices that point at no `v`, `vt` or `vn` line,
/// naming the line. tobj checks positions itself but computes texture and normal offsets
/// before its bounds check, which overflows (a panic in debug builds) on an index of 0 or one
/// far out of range. tobj refuses a line that is not UTF-8 only when it reaches it, after the
/// lines before it, so such text is refused here before tobj reads any of it.
fn check_face_indices(text: &[u8], name: &str) -> Result<()> {
    let text = std::str::from_utf8(text).map_err(|e| {
        let line = text[..e.valid_up_to()]
            .iter()
            .filter(|&&b| b == b'\n')
            .count();
        Error::Format {
            path: name.to_string(),
            message: format!("line {}: not UTF-8 text", line + 1),
        }
    })?;
    const KINDS: [&str; 3] = ["vertex", "texture coordinate", "normal"];
    // Which element a line's first word declares: 0 `v`, 1 `vt`, 2 `vn`.
    let kind_of = |word: Option<&str>| match word {
        Some("v") => Some(0),
        Some("vt") => Some(1),
        Some("vn") => Some(2),
        _ => None,
    };
    let mut totals = [0usize; 3];
    for line in text.lines() {
        if let Some(kind) = kind_of(line.split_whitespace().next()) {
            totals[kind] += 1;
        }
    }
    let mut seen = [0usize; 3];
    for (number, line) in text.lines().enumerate() {
        let mut words = line.split_whitespace();
        let first = words.next();
        if let Some(kind) = kind_of(first) {
            seen[kind] += 1;
        } else if first == Some("f") {
            for corner in words {
                for (kind, field) in corner.split('/').enumerate().take(3) {
                    // Fields that are not integers are refused by tobj with its own error.
                    let Ok(index) = field.parse::<i64>() else {
                        continue;
                    };
                    // Negative indices count back from the elements read so far.
                    let fine = if index < 0 {
                        index.unsigned_abs() as usize <= seen[kind]
                    } else {
                        index >= 1 && index as u64 <= totals[kind] as u64
                    };
                    if !fine {
                        return Err(Error::Format {
                            path: name.to_string(),
                            message: format!(
                                "line {}: face index {index} names no {} ({} in the file, {} \
                                     before this line)",
                                number + 1,
                                KINDS[kind],
                                totals[kind],
                                seen[kind]
                            ),
                        });
                    }
                }
            }
        }
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn face_indices_naming_nothing_are_refused_by_line() {
        let square = "v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nvt 0 0\nvt 1 0\nvt 1 1\nvt 0 1\n";
        let fine = format!("{square}f 1/1 2/2 3/3 4/-1\n");
        parse_obj(fine.as_bytes(), "ok.obj", "ok").unwrap();
        // The fuzzer's find: a relative texture index before any `vt` line (tobj overflowed).
        let cases = [
            (
                "v 0 0 0\nv 1 0 0\nv 1 1 0\nf 1/1 2/-2 3/3\nvt 0 0\n",
                "line 4",
                "-2",
            ),
            (&*format!("{square}f 1/0 2/2 3/3\n"), "line 9", "index 0"),
            (
                &*format!("{square}f 1/1 2/2 3/9\n"),
                "line 9",
                "texture coordinate",
            ),
            (&*format!("{square}f 1//1 2//1 3//1\n"), "line 9", "normal"),
            (&*format!("{square}f 1 2 -5\n"), "line 9", "vertex"),
            (
                &*format!("{square}f 1 2 9223372036854775807\n"),
                "line 9",
                "vertex",
            ),
            (
                &*format!("{square}f 1/1 2/-2222222222 3/3\n"),
                "line 9",
                "-2222222222",
            ),
        ];
        for (text, line, what) in cases {
            let message = parse_obj(text.as_bytes(), "bad.obj", "bad")
                .unwrap_err()
                .to_string();
            assert!(message.contains("bad.obj"), "{message}");
            assert!(
                message.contains(line) && message.contains(what),
                "{message}"
            );
        }
    }

    #[test]
    fn text_that_is_not_utf8_is_refused_by_line_before_tobj_reads_it() {
        // The fuzzer's second find: an out-of-range texture index on line 9, and a byte that
        // is not UTF-8 on line 10. tobj read line 9 before refusing line 10, and overflowed.
        let text = b"v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nvt 0 0\nvt 1 0\nvt 1 1\nvt 0 1\n\
                     f 1/1 2/-2222222222 3/3\nvt \x83 1\n";
        let message = parse_obj(text, "bad.obj", "bad").unwrap_err().to_string();
        assert!(
            message.contains("bad.obj") && message.contains("line 10: not UTF-8"),
            "{message}"
        );
    }

    #[test]
    fn round_trip_keeps_panels_and_welds_seams() {
        let mut g = crate::builtin::tube_for_tests();
        // Two panels: front and back halves of the tube.
        g.panels = vec!["front".into(), "back".into()];
        g.triangle_panels = (0..g.triangles.len() as u32).map(|t| t % 2).collect();
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("tube.obj");
        let mut f = std::fs::File::create(&path).unwrap();
        write_obj(&mut f, &g, None).unwrap();
        drop(f);
        let back = read_obj(&path).unwrap();
        back.validate().unwrap();
        assert_eq!(back.panels, g.panels);
        assert_eq!(back.positions.len(), g.positions.len(), "seams welded");
        assert_eq!(back.triangles.len(), g.triangles.len());
        // Triangles come back grouped by panel: match them by corner positions.
        let key = |gm: &Garment, t: usize| {
            let mut corners: Vec<[i64; 3]> = gm.triangles[t]
                .iter()
                .map(|&v| gm.positions[v as usize].map(|c| (c * 1e5).round() as i64))
                .collect();
            corners.sort();
            (corners, gm.panels[gm.triangle_panels[t] as usize].clone())
        };
        let mut a: Vec<_> = (0..g.triangles.len()).map(|t| key(&g, t)).collect();
        let mut b: Vec<_> = (0..back.triangles.len()).map(|t| key(&back, t)).collect();
        a.sort();
        b.sort();
        assert_eq!(a, b);
        for t in 0..back.triangles.len() {
            for k in 0..3 {
                let uv = back.uvs[back.uv_triangles[t][k] as usize];
                assert!(uv.iter().all(|c| (0.0..=1.0).contains(c)));
            }
        }
    }

    #[test]
    fn unreadable_files_name_the_file() {
        let dir = tempfile::tempdir().unwrap();
        let bad = dir.path().join("no_uv.obj");
        std::fs::write(&bad, "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n").unwrap();
        let g = read_obj(&bad).unwrap();
        assert!(g.uv_triangles.is_empty(), "read, reported by the check");
        let empty = dir.path().join("empty.obj");
        std::fs::write(&empty, "v 0 0 0\n").unwrap();
        let e = read_obj(&empty).unwrap_err().to_string();
        assert!(e.contains("empty.obj") && e.contains("no faces"), "{e}");
        let missing = read_obj(&dir.path().join("missing.obj"))
            .unwrap_err()
            .to_string();
        assert!(missing.contains("missing.obj"), "{missing}");
    }

    #[test]
    fn ply_header_and_size() {
        let g = crate::builtin::tube_for_tests();
        let mut bytes = Vec::new();
        write_ply(&mut bytes, &g).unwrap();
        let header_end = bytes
            .windows(11)
            .position(|w| w == b"end_header\n")
            .unwrap()
            + 11;
        let header = std::str::from_utf8(&bytes[..header_end]).unwrap();
        assert!(header.contains(&format!("element vertex {}", g.positions.len())));
        assert!(header.contains(&format!("element face {}", g.triangles.len())));
        let body = bytes.len() - header_end;
        assert_eq!(
            body,
            g.positions.len() * 12 + g.triangles.len() * (1 + 12 + 1 + 24 + 4)
        );
    }
}
