//! Meshes users bring (a scan, an artist's garment, a frame of a capture): OBJ or PLY read
//! alike, coincident vertices welded, UV charts checked for overlap (a mesh without usable UVs
//! gets new ones from [`crate::unwrap`]).
//!
//! PLY is read by `ply-rs` (ASCII and both binary layouts).

use std::path::Path;

use ply_rs::ply::{DefaultElement, Property};

use crate::error::{Error, Result};
use crate::mesh::Garment;

/// Texels per side of the grid UV overlap is measured on.
const OVERLAP_GRID: usize = 256;

/// Reads an OBJ or a PLY mesh (by its extension; anything else is read as OBJ). A mesh
/// without UVs reads with none.
pub fn read_mesh(path: &Path) -> Result<Garment> {
    let ply = path
        .extension()
        .is_some_and(|e| e.eq_ignore_ascii_case("ply"));
    if !ply {
        return crate::read_obj(path);
    }
    let bytes = files::read(path, files::limits::MESH, "mesh")?;
    let name = path
        .file_stem()
        .map(|s| s.to_string_lossy().into_owned())
        .unwrap_or_default();
    parse_ply(&bytes, &path.display().to_string(), &name)
}

/// The header's element counts, read before `ply-rs` sees them: it unwraps their parse, so a
/// count past `u64` (found by the `ply` fuzz target) would panic inside it.
fn check_element_counts(bytes: &[u8]) -> std::result::Result<(), String> {
    let header = bytes
        .split(|&b| b == b'\n')
        .take_while(|l| !l.starts_with(b"end_header"));
    for line in header {
        let line = String::from_utf8_lossy(line);
        let mut words = line.split_whitespace();
        if words.next() == Some("element") {
            let (name, count) = (words.next().unwrap_or(""), words.next().unwrap_or(""));
            if count.parse::<u64>().is_err() {
                return Err(format!(
                    "element '{name}' has the count '{count}', not a number"
                ));
            }
        }
    }
    Ok(())
}

/// A PLY file's bytes as a garment of one panel: `vertex` x, y, z; `face` `vertex_indices`
/// (or `vertex_index`), polygons fanned into triangles; UVs from per-corner `texcoord` lists
/// (what [`crate::write_ply`] writes) or per-vertex `s`/`t`, `u`/`v` or `texture_u`/`texture_v`.
pub fn parse_ply(bytes: &[u8], path: &str, name: &str) -> Result<Garment> {
    let bad = |message: String| Error::Format {
        path: path.to_string(),
        message,
    };
    check_element_counts(bytes).map_err(bad)?;
    let parser = ply_rs::parser::Parser::<DefaultElement>::new();
    let mut reader = std::io::BufReader::new(bytes);
    let header = parser
        .read_header(&mut reader)
        .map_err(|e| bad(format!("not a readable PLY header: {e}")))?;
    // Every element takes at least a byte: a count past the file's size is a lie that would
    // otherwise be allocated for.
    for (element, def) in &header.elements {
        if def.count > bytes.len() {
            return Err(bad(format!(
                "element '{element}' claims {} entries in a file of {} bytes",
                def.count,
                bytes.len()
            )));
        }
    }
    let payload = parser
        .read_payload(&mut reader, &header)
        .map_err(|e| bad(format!("not a readable PLY body: {e}")))?;
    let vertices = payload.get("vertex").map(Vec::as_slice).unwrap_or_default();
    let faces = payload.get("face").map(Vec::as_slice).unwrap_or_default();
    if faces.is_empty() {
        return Err(bad("no faces".into()));
    }
    let mut positions = Vec::with_capacity(vertices.len());
    let mut vertex_uvs = Vec::new();
    for (i, v) in vertices.iter().enumerate() {
        let coordinate = |key: &str| {
            scalar(v.get(key)).ok_or_else(|| bad(format!("vertex {i} has no number '{key}'")))
        };
        positions.push([coordinate("x")?, coordinate("y")?, coordinate("z")?]);
        let uv = [("s", "t"), ("u", "v"), ("texture_u", "texture_v")]
            .iter()
            .find_map(|(u, w)| Some([scalar(v.get(*u))?, scalar(v.get(*w))?]));
        if let Some(uv) = uv {
            vertex_uvs.push(uv);
        }
    }
    let per_vertex_uvs = !vertex_uvs.is_empty() && vertex_uvs.len() == positions.len();
    let mut g = Garment {
        name: name.to_string(),
        positions,
        panels: vec![name.to_string()],
        ..Garment::default()
    };
    let mut corner_uvs = true;
    for (f, face) in faces.iter().enumerate() {
        let indices = face
            .get("vertex_indices")
            .or_else(|| face.get("vertex_index"))
            .and_then(list)
            .ok_or_else(|| bad(format!("face {f} has no vertex_indices list")))?;
        if indices.len() < 3 {
            return Err(bad(format!(
                "face {f} has {} corners (3 or more)",
                indices.len()
            )));
        }
        let corners: Vec<u32> = indices
            .iter()
            .map(|&i| {
                u32::try_from(i)
                    .ok()
                    .filter(|&i| (i as usize) < g.positions.len())
                    .ok_or_else(|| bad(format!("face {f} names vertex {i}, which is not there")))
            })
            .collect::<Result<_>>()?;
        let texcoord = face.get("texcoord").and_then(float_list);
        let texcoord = texcoord.filter(|t| t.len() == 2 * corners.len());
        corner_uvs &= texcoord.is_some();
        for k in 1..corners.len() - 1 {
            let fan = [0, k, k + 1];
            g.triangles.push(fan.map(|c| corners[c]));
            g.triangle_panels.push(0);
            if let Some(t) = &texcoord {
                let first = g.uvs.len() as u32;
                g.uvs.extend(fan.map(|c| [t[2 * c], t[2 * c + 1]]));
                g.uv_triangles.push([first, first + 1, first + 2]);
            }
        }
    }
    if !corner_uvs {
        g.uvs.clear();
        g.uv_triangles.clear();
        if per_vertex_uvs {
            g.uvs = vertex_uvs;
            g.uv_triangles = g.triangles.clone();
        }
    }
    Ok(g)
}

fn scalar(p: Option<&Property>) -> Option<f64> {
    Some(match p? {
        Property::Float(x) => f64::from(*x),
        Property::Double(x) => *x,
        Property::Char(x) => f64::from(*x),
        Property::UChar(x) => f64::from(*x),
        Property::Short(x) => f64::from(*x),
        Property::UShort(x) => f64::from(*x),
        Property::Int(x) => f64::from(*x),
        Property::UInt(x) => f64::from(*x),
        _ => return None,
    })
}

fn list(p: &Property) -> Option<Vec<i64>> {
    Some(match p {
        Property::ListChar(v) => v.iter().map(|&x| i64::from(x)).collect(),
        Property::ListUChar(v) => v.iter().map(|&x| i64::from(x)).collect(),
        Property::ListShort(v) => v.iter().map(|&x| i64::from(x)).collect(),
        Property::ListUShort(v) => v.iter().map(|&x| i64::from(x)).collect(),
        Property::ListInt(v) => v.iter().map(|&x| i64::from(x)).collect(),
        Property::ListUInt(v) => v.iter().map(|&x| i64::from(x)).collect(),
        _ => return None,
    })
}

fn float_list(p: &Property) -> Option<Vec<f64>> {
    Some(match p {
        Property::ListFloat(v) => v.iter().map(|&x| f64::from(x)).collect(),
        Property::ListDouble(v) => v.clone(),
        _ => return None,
    })
}

/// Welds vertices closer than `tolerance` (m) into the first of them, as exporters that split
/// vertices at UV seams or per face leave them; UVs stay per corner. Returns how many vertices
/// went. Triangles that collapse are left for [`crate::repair`] to remove.
pub fn weld(g: &mut Garment, tolerance: f64) -> usize {
    let cell = tolerance.max(1e-12);
    let key = |p: &[f64; 3]| p.map(|c| (c / cell).floor() as i64);
    let mut grid: std::collections::HashMap<[i64; 3], Vec<u32>> = Default::default();
    let mut keep = vec![0u32; g.positions.len()];
    let mut kept: Vec<[f64; 3]> = Vec::with_capacity(g.positions.len());
    for (i, p) in g.positions.iter().enumerate() {
        let k = key(p);
        let mut found = None;
        'search: for dx in -1..=1 {
            for dy in -1..=1 {
                for dz in -1..=1 {
                    let cell = [
                        k[0].saturating_add(dx),
                        k[1].saturating_add(dy),
                        k[2].saturating_add(dz),
                    ];
                    let near = grid.get(&cell);
                    for &j in near.into_iter().flatten() {
                        let q = kept[j as usize];
                        let d2: f64 = (0..3).map(|a| (p[a] - q[a]).powi(2)).sum();
                        if d2 <= tolerance * tolerance {
                            found = Some(j);
                            break 'search;
                        }
                    }
                }
            }
        }
        keep[i] = found.unwrap_or_else(|| {
            let j = kept.len() as u32;
            kept.push(*p);
            grid.entry(k).or_default().push(j);
            j
        });
    }
    let welded = g.positions.len() - kept.len();
    g.positions = kept;
    for t in &mut g.triangles {
        *t = t.map(|v| keep[v as usize]);
    }
    for labelled in g.vertex_labels.values_mut() {
        for v in labelled.iter_mut() {
            *v = keep[*v as usize];
        }
        labelled.sort_unstable();
        labelled.dedup();
    }
    welded
}

/// The fraction of the UV area covered more than once: rasterized on a 256 x 256 grid, texels
/// covered by two or more triangles over texels covered at all (0 for a valid atlas, up to 1
/// when every chart lies on another; 1 for a mesh without UVs).
pub fn uv_overlap(g: &Garment) -> f64 {
    if g.uv_triangles.len() != g.triangles.len() || g.uvs.is_empty() {
        return 1.0;
    }
    let n = OVERLAP_GRID;
    let mut hits = vec![0u16; n * n];
    for t in &g.uv_triangles {
        let [a, b, c] = t.map(|i| g.uvs.get(i as usize).copied().unwrap_or([0.0; 2]));
        let area = (b[0] - a[0]) * (c[1] - a[1]) - (c[0] - a[0]) * (b[1] - a[1]);
        if area.abs() < 1e-14 {
            continue;
        }
        let lo = |k: usize| (a[k].min(b[k]).min(c[k]) * n as f64).floor().max(0.0) as usize;
        let hi = |k: usize| ((a[k].max(b[k]).max(c[k]) * n as f64).ceil() as usize).min(n);
        for y in lo(1)..hi(1) {
            for x in lo(0)..hi(0) {
                let p = [(x as f64 + 0.5) / n as f64, (y as f64 + 0.5) / n as f64];
                let edge = |u: [f64; 2], v: [f64; 2]| {
                    ((v[0] - u[0]) * (p[1] - u[1]) - (p[0] - u[0]) * (v[1] - u[1])) * area.signum()
                };
                if edge(a, b) >= 0.0 && edge(b, c) >= 0.0 && edge(c, a) >= 0.0 {
                    let h = &mut hits[y * n + x];
                    *h = h.saturating_add(1);
                }
            }
        }
    }
    let covered = hits.iter().filter(|&&h| h > 0).count();
    let twice = hits.iter().filter(|&&h| h > 1).count();
    if covered == 0 {
        1.0
    } else {
        twice as f64 / covered as f64
    }
}

/// The median edge length, m (0 for a mesh without triangles).
pub fn median_edge_length(g: &Garment) -> f64 {
    let mut lengths: Vec<f64> = g
        .triangles
        .iter()
        .flat_map(|t| {
            (0..3).map(move |k| {
                let (a, b) = (
                    g.positions[t[k] as usize],
                    g.positions[t[(k + 1) % 3] as usize],
                );
                (0..3).map(|c| (a[c] - b[c]).powi(2)).sum::<f64>().sqrt()
            })
        })
        .collect();
    if lengths.is_empty() {
        return 0.0;
    }
    let mid = lengths.len() / 2;
    *lengths.select_nth_unstable_by(mid, f64::total_cmp).1
}

/// Splits every triangle into four at its edges' midpoints (positions and per-corner UVs),
/// halving the edge length: what makes a coarse mesh (an artist's low-poly garment) fine enough
/// for the engine, whose cloth bends only at edges. Labels keep their old vertices.
pub fn subdivide(g: &mut Garment) {
    let mut midpoints = std::collections::HashMap::new();
    let mut uv_midpoints = std::collections::HashMap::new();
    let mut triangles = Vec::with_capacity(4 * g.triangles.len());
    let mut uv_triangles = Vec::with_capacity(4 * g.uv_triangles.len());
    let mut panels = Vec::with_capacity(4 * g.triangle_panels.len());
    let with_uvs = g.uv_triangles.len() == g.triangles.len();
    for (t, tri) in g.triangles.clone().iter().enumerate() {
        let mut mid = |a: u32, b: u32, g: &mut Garment| -> u32 {
            *midpoints.entry((a.min(b), a.max(b))).or_insert_with(|| {
                let (p, q) = (g.positions[a as usize], g.positions[b as usize]);
                g.positions.push([0, 1, 2].map(|c| 0.5 * (p[c] + q[c])));
                g.positions.len() as u32 - 1
            })
        };
        let [a, b, c] = *tri;
        let (ab, bc, ca) = (mid(a, b, g), mid(b, c, g), mid(c, a, g));
        triangles.extend([[a, ab, ca], [ab, b, bc], [ca, bc, c], [ab, bc, ca]]);
        panels.extend([g.triangle_panels.get(t).copied().unwrap_or(0); 4]);
        if with_uvs {
            let [u, v, w] = g.uv_triangles[t];
            let mut uv_mid = |a: u32, b: u32| -> u32 {
                *uv_midpoints.entry((a.min(b), a.max(b))).or_insert_with(|| {
                    let (p, q) = (g.uvs[a as usize], g.uvs[b as usize]);
                    g.uvs.push([0.5 * (p[0] + q[0]), 0.5 * (p[1] + q[1])]);
                    g.uvs.len() as u32 - 1
                })
            };
            let (uv, vw, wu) = (uv_mid(u, v), uv_mid(v, w), uv_mid(w, u));
            uv_triangles.extend([[u, uv, wu], [uv, v, vw], [wu, vw, w], [uv, vw, wu]]);
        }
    }
    g.triangles = triangles;
    g.uv_triangles = uv_triangles;
    g.triangle_panels = panels;
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn an_element_count_past_u64_is_refused_not_a_panic() {
        // The input the `ply` fuzz target found (2026-12-06), cut to its header.
        let bytes = b"ply\nformat ascii 1.0\nelement vertex 4\nproperty float x\n\
                      element face 3333333333333333333333333333333333333333333333331\n\
                      property list uchar int vertex_indices\nend_header\n0 0 0\n";
        let e = parse_ply(bytes, "crash.ply", "crash").unwrap_err();
        assert!(
            matches!(&e, Error::Format { path, message } if path == "crash.ply" && message.contains("'face'")),
            "{e}"
        );
    }

    fn tube() -> Garment {
        crate::builtin::tube_for_tests()
    }

    #[test]
    fn a_ply_written_here_reads_back_with_its_uvs() {
        let g = tube();
        let mut bytes = Vec::new();
        crate::write_ply(&mut bytes, &g).unwrap();
        let back = parse_ply(&bytes, "tube.ply", "tube").unwrap();
        assert_eq!(back.triangles, g.triangles);
        assert_eq!(back.positions.len(), g.positions.len());
        for (p, q) in back.positions.iter().zip(&g.positions) {
            assert!((0..3).all(|k| (p[k] - q[k]).abs() < 1e-6));
        }
        assert!(uv_overlap(&back) < 0.01, "{}", uv_overlap(&back));
    }

    #[test]
    fn an_ascii_ply_with_quads_and_no_uvs_reads_as_triangles() {
        let text = "ply\nformat ascii 1.0\nelement vertex 4\nproperty float x\nproperty float y\n\
                    property float z\nelement face 1\nproperty list uchar int vertex_indices\n\
                    end_header\n0 0 0\n1 0 0\n1 1 0\n0 1 0\n4 0 1 2 3\n";
        let g = parse_ply(text.as_bytes(), "quad.ply", "quad").unwrap();
        assert_eq!(g.triangles, vec![[0, 1, 2], [0, 2, 3]]);
        assert!(g.uv_triangles.is_empty());
        assert_eq!(uv_overlap(&g), 1.0);
        let lying = text.replace("element vertex 4", "element vertex 4000000");
        let e = parse_ply(lying.as_bytes(), "quad.ply", "quad").unwrap_err();
        assert!(
            matches!(&e, Error::Format { path, message } if path == "quad.ply" && message.contains("claims 4000000")),
            "{e}"
        );
        let out_of_range = text.replace("4 0 1 2 3", "4 0 1 2 9");
        let e = parse_ply(out_of_range.as_bytes(), "quad.ply", "quad").unwrap_err();
        assert!(e.to_string().contains("vertex 9"), "{e}");
    }

    #[test]
    fn subdividing_halves_the_edges_and_keeps_the_surface_and_its_uvs() {
        let mut g = tube();
        let (before, t) = (median_edge_length(&g), g.triangles.len());
        subdivide(&mut g);
        assert_eq!(g.triangles.len(), 4 * t);
        let after = median_edge_length(&g);
        assert!((after / before - 0.5).abs() < 0.1, "{before} -> {after}");
        g.validate().unwrap();
        assert!(
            crate::check(&g).findings.is_empty(),
            "{:?}",
            crate::check(&g)
        );
        assert!(uv_overlap(&g) < 0.01);
    }

    #[test]
    fn welding_joins_split_vertices_and_keeps_corner_uvs() {
        let mut g = tube();
        let (n, t) = (g.positions.len(), g.triangles.len());
        // Split every triangle's corners into vertices of their own, as a triangle soup.
        let soup: Vec<[f64; 3]> = g
            .triangles
            .iter()
            .flat_map(|t| t.map(|v| g.positions[v as usize]))
            .collect();
        g.triangles = (0..t as u32)
            .map(|k| [3 * k, 3 * k + 1, 3 * k + 2])
            .collect();
        g.positions = soup;
        let gone = weld(&mut g, 1e-6);
        assert_eq!(g.positions.len(), n);
        // Coordinates past any grid cell (a hostile file) weld without overflowing.
        let mut far = tube();
        far.positions[0] = [1e300, -1e300, f64::NAN];
        far.positions[1] = [1e300, -1e300, 0.0];
        weld(&mut far, 1e-6);
        assert_eq!(gone, 3 * t - n);
        let corners = |m: &Garment| -> Vec<[[f64; 3]; 3]> {
            m.triangles
                .iter()
                .map(|t| t.map(|v| m.positions[v as usize]))
                .collect()
        };
        assert_eq!(
            corners(&g),
            corners(&tube()),
            "the same triangles, renumbered"
        );
    }
}
