//! A recording scored against a capture: ground truth whose meshes share no vertices with the
//! template (a folder of OBJ, PLY or pickled frames, one topology per frame or one for all;
//! the pickles as 4D-Dress ships them, `mesh-f*.pkl` with `vertices` and `faces`, or its
//! extracted `cloth-f*.pkl`, one such dict per garment label, read without running their
//! code by `motions::pickle`). Only the
//! correspondence-free metrics apply: E_CD, E_CD_cm and E_n between surface samples, E_c of
//! the scored garment against the body, and the distribution of nearest-point distances (its
//! 90th percentile in cm, which D-Garment reports for real data). E_v, E_b, E_s and E_d need
//! the same vertices on both sides and are reported as not applicable.

use std::path::{Path, PathBuf};

use motions::BodyModel;
use serde::Serialize;

use super::{BodySurface, FRAME_STRIDE, P3, Scorer, SurfaceSamples};
use crate::recording::Recording;
use crate::{Error, Result};

/// The scores of one frame (or their mean) against a capture.
#[allow(non_snake_case)]
#[derive(Debug, Clone, Copy, Default, PartialEq, Serialize)]
pub struct CaptureScores {
    /// 100 x the sum of both directions' mean squared nearest-sample distances, 100 m^2.
    pub E_CD: f64,
    /// The mean of both directions' mean nearest-sample distances, cm.
    pub E_CD_cm: f64,
    /// The sum of both directions' mean 1 - |cos| between paired sample normals.
    pub E_n: f64,
    /// Surface samples of the scored garment inside the body, %.
    pub E_c: f64,
    /// Its vertices inside the body, %.
    pub E_c_vertex: f64,
    /// The 90th percentile of the nearest-sample distances, both directions pooled, cm.
    pub distance_p90_cm: f64,
}

impl CaptureScores {
    /// Names and units, in field order.
    pub const UNITS: [(&'static str, &'static str); 6] = [
        (
            "E_CD",
            "100 m^2 (sum of both directions' mean squared distances, x 100)",
        ),
        ("E_CD_cm", "cm (mean nearest distance, symmetric)"),
        ("E_n", "sum of both directions' mean 1 - |cos|"),
        ("E_c", "% of garment surface samples inside the body"),
        ("E_c_vertex", "% of garment vertices inside the body"),
        (
            "distance_p90_cm",
            "cm, 90th percentile of nearest distances (both directions)",
        ),
    ];

    /// The values, in field order.
    pub fn values(&self) -> [f64; 6] {
        [
            self.E_CD,
            self.E_CD_cm,
            self.E_n,
            self.E_c,
            self.E_c_vertex,
            self.distance_p90_cm,
        ]
    }

    fn mean(frames: &[CaptureScores]) -> CaptureScores {
        let n = frames.len().max(1) as f64;
        let sum = |f: fn(&CaptureScores) -> f64| frames.iter().map(f).sum::<f64>() / n;
        CaptureScores {
            E_CD: sum(|s| s.E_CD),
            E_CD_cm: sum(|s| s.E_CD_cm),
            E_n: sum(|s| s.E_n),
            E_c: sum(|s| s.E_c),
            E_c_vertex: sum(|s| s.E_c_vertex),
            distance_p90_cm: sum(|s| s.distance_p90_cm),
        }
    }
}

/// The metrics that need one vertex order on both sides.
pub const NOT_APPLICABLE: [&str; 4] = ["E_v", "E_b", "E_s", "E_d"];

/// Nearest-sample distances and normal terms from `from` to `to`.
fn directed(from: &SurfaceSamples, to: &SurfaceSamples) -> (Vec<f64>, f64) {
    let tree = to.tree();
    let mut normal = 0.0;
    let distances = from
        .points
        .iter()
        .zip(&from.normals)
        .map(|(p, n)| {
            let hit = tree.nearest_one::<kiddo::SquaredEuclidean>(p);
            normal += 1.0 - super::dot(*n, to.normals[hit.item as usize]).abs();
            hit.distance.sqrt()
        })
        .collect();
    (distances, normal / from.points.len().max(1) as f64)
}

/// Scores the garment `pred` (over `pred_triangles`) against the captured mesh `truth` (over
/// `truth_triangles`) at `frame`, with `body` for E_c; `scorer` draws the samples.
pub fn score_frame(
    scorer: &Scorer,
    pred: &[P3],
    truth: &[P3],
    truth_triangles: &[[u32; 3]],
    body: &BodySurface,
    frame: usize,
) -> CaptureScores {
    let seed = scorer.frame_seed(frame);
    let sp = SurfaceSamples::new(pred, &scorer.triangles, scorer.samples, seed);
    let st = SurfaceSamples::new(truth, truth_triangles, scorer.samples, seed ^ 0xC0FF_EE00);
    let (d1, n1) = directed(&sp, &st);
    let (d2, n2) = directed(&st, &sp);
    let mean = |d: &[f64]| d.iter().sum::<f64>() / d.len().max(1) as f64;
    let mean_sq = |d: &[f64]| d.iter().map(|x| x * x).sum::<f64>() / d.len().max(1) as f64;
    let mut pooled: Vec<f64> = d1.iter().chain(&d2).copied().collect();
    let p90 = if pooled.is_empty() {
        0.0
    } else {
        let k = ((pooled.len() as f64 * 0.9).ceil() as usize).clamp(1, pooled.len()) - 1;
        *pooled.select_nth_unstable_by(k, f64::total_cmp).1
    };
    let (e_c, e_c_vertex) = scorer.inside(&sp, pred, body, seed);
    CaptureScores {
        E_CD: 100.0 * (mean_sq(&d1) + mean_sq(&d2)),
        E_CD_cm: 100.0 * 0.5 * (mean(&d1) + mean(&d2)),
        E_n: n1 + n2,
        E_c: e_c,
        E_c_vertex: e_c_vertex,
        distance_p90_cm: 100.0 * p90,
    }
}

/// A recording scored against a capture: the mean over the scored frames and each of them.
#[derive(Debug, Clone)]
pub struct CaptureCompared {
    /// The mean over the scored frames.
    pub mean: CaptureScores,
    /// Each scored frame with its index.
    pub per_frame: Vec<(usize, CaptureScores)>,
    /// Frames both have.
    pub frames: usize,
}

/// The largest pickled capture frame read, bytes (a 4D-Dress scan of 80k faces is ~10 MB).
const MAX_PICKLE_BYTES: u64 = 512 << 20;

/// The mesh files of a capture folder (`.obj`, `.ply` or `.pkl`), in name order: frame k is
/// the k-th.
pub fn capture_frames(dir: &Path) -> Result<Vec<PathBuf>> {
    let refuse = |message: String| Error::Recording {
        path: dir.display().to_string(),
        message,
    };
    let files = files::files_with_extensions(dir, &["obj", "ply", "pkl"])
        .map_err(|e| refuse(format!("unreadable folder: {e}")))?;
    if files.is_empty() {
        return Err(refuse("holds no .obj, .ply or .pkl frames".into()));
    }
    Ok(files)
}

/// One capture frame's vertices and triangles. A pickle holding one dict per garment label
/// (4D-Dress's `cloth-f*.pkl`) needs `garment`, the label to score against.
pub fn read_capture_frame(path: &Path, garment: Option<&str>) -> Result<(Vec<P3>, Vec<[u32; 3]>)> {
    let refuse = |message: String| Error::Recording {
        path: path.display().to_string(),
        message,
    };
    let pickled = path
        .extension()
        .is_some_and(|e| e.eq_ignore_ascii_case("pkl"));
    let (positions, triangles) = if pickled {
        let bytes = files::read(path, MAX_PICKLE_BYTES, "capture frame")?;
        let value = motions::pickle::read(&bytes).map_err(refuse)?;
        pickled_mesh(&value, garment).map_err(refuse)?
    } else {
        let mesh = garments::read_mesh(path).map_err(|e| refuse(e.to_string()))?;
        (mesh.positions, mesh.triangles)
    };
    if positions.iter().flatten().any(|c| !c.is_finite()) {
        return Err(refuse("a vertex is not finite".into()));
    }
    Ok((positions, triangles))
}

/// The mesh of a pickled frame: `vertices` (N x 3) and `faces` (M x 3) at the top, or under
/// the key `garment`.
fn pickled_mesh(
    value: &motions::pickle::Value,
    garment: Option<&str>,
) -> std::result::Result<(Vec<P3>, Vec<[u32; 3]>), String> {
    use motions::pickle::Value;
    let labels = || match value {
        Value::Dict(items) => items
            .iter()
            .filter(|(_, v)| v.get("vertices").is_some())
            .filter_map(|(k, _)| match k {
                Value::Str(s) => Some(s.clone()),
                _ => None,
            })
            .collect::<Vec<_>>(),
        _ => Vec::new(),
    };
    let mesh = match (value.get("vertices"), garment) {
        (Some(_), _) => value,
        (None, Some(label)) => value.get(label).ok_or_else(|| {
            format!(
                "holds no garment '{label}' (it holds: {})",
                labels().join(", ")
            )
        })?,
        (None, None) if labels().is_empty() => {
            return Err("holds no `vertices` and `faces` (not a mesh pickle)".into());
        }
        (None, None) => {
            return Err(format!(
                "holds several garments ({}): name the one to score with --capture-garment",
                labels().join(", ")
            ));
        }
    };
    let array = |key: &str| match mesh.get(key) {
        Some(Value::Array(a)) if a.shape.len() == 2 && a.shape[1] == 3 => Ok(a.data.clone()),
        Some(Value::Array(a)) => Err(format!("`{key}` has shape {:?}, not N x 3", a.shape)),
        _ => Err(format!("`{key}` is missing or not an array")),
    };
    let vertices = array("vertices")?;
    let faces = array("faces")?;
    let n = vertices.len() / 3;
    let positions = vertices
        .chunks_exact(3)
        .map(|c| [c[0], c[1], c[2]])
        .collect();
    let triangles = faces
        .chunks_exact(3)
        .map(|f| {
            let index = |x: f64| {
                (x >= 0.0 && x.fract() == 0.0 && (x as usize) < n)
                    .then_some(x as u32)
                    .ok_or_else(|| format!("a face refers to vertex {x}, past the {n} vertices"))
            };
            Ok([index(f[0])?, index(f[1])?, index(f[2])?])
        })
        .collect::<std::result::Result<Vec<_>, String>>()?;
    if triangles.is_empty() {
        return Err("has no faces".into());
    }
    Ok((positions, triangles))
}

/// Scores recording `b` (its garment, its body for E_c) against the capture frames in `dir`
/// (frame k of the recording against the k-th file), every [`FRAME_STRIDE`]-th frame.
pub fn compare_with_capture(
    dir: &Path,
    garment: Option<&str>,
    b: &Recording,
    b_path: &Path,
    model: &BodyModel,
    seed: u64,
) -> Result<CaptureCompared> {
    let files = capture_frames(dir)?;
    let frames = files.len().min(b.garment.len());
    if frames == 0 {
        return Err(Error::Recording {
            path: b_path.display().to_string(),
            message: "has no frames to score".into(),
        });
    }
    let scorer = Scorer::new(&b.template.positions, &b.template.triangles, seed);
    let mut per_frame = Vec::new();
    for k in (0..frames).step_by(FRAME_STRIDE) {
        let (truth, truth_triangles) = read_capture_frame(&files[k], garment)?;
        let body = b.body_at(model, k, b_path)?;
        let surface = BodySurface {
            vertices: &body.vertices,
            triangles: &body.faces,
        };
        let pred: Vec<P3> = b.garment[k].iter().map(|p| p.map(f64::from)).collect();
        let s = score_frame(&scorer, &pred, &truth, &truth_triangles, &surface, k);
        per_frame.push((k, s));
    }
    let mean = CaptureScores::mean(&per_frame.iter().map(|(_, s)| *s).collect::<Vec<_>>());
    Ok(CaptureCompared {
        mean,
        per_frame,
        frames,
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A 1 m square in the x-z plane at height `y`, `n` x `n` cells.
    fn sheet(n: u32, y: f64) -> garments::Garment {
        let mut g = garments::Garment::default();
        for i in 0..=n {
            for j in 0..=n {
                g.positions
                    .push([i as f64 / n as f64, y, j as f64 / n as f64]);
            }
        }
        for i in 0..n {
            for j in 0..n {
                let v = i * (n + 1) + j;
                g.triangles.push([v, v + 1, v + n + 1]);
                g.triangles.push([v + 1, v + n + 2, v + n + 1]);
            }
        }
        g
    }

    #[test]
    fn pickled_frames_are_read_and_a_garment_is_picked_by_label() {
        let fixtures =
            Path::new(env!("CARGO_MANIFEST_DIR")).join("../motions/tests/fixtures/pickle");
        let (v, t) = read_capture_frame(&fixtures.join("mesh_fortran.pkl"), None).unwrap();
        assert_eq!(v.len(), 4);
        assert_eq!(v[1], [1.5, 2.0, 2.5]);
        assert_eq!(t, vec![[0, 1, 2], [0, 2, 3]]);
        let cloth = fixtures.join("cloth_two.pkl");
        let e = read_capture_frame(&cloth, None).unwrap_err().to_string();
        assert!(
            e.contains("(upper, lower)") && e.contains("--capture-garment"),
            "{e}"
        );
        let (lower, _) = read_capture_frame(&cloth, Some("lower")).unwrap();
        assert_eq!(lower[2], [1.0, 1.0, 1.0]);
        let e = read_capture_frame(&cloth, Some("outer"))
            .unwrap_err()
            .to_string();
        assert!(
            e.contains("no garment 'outer' (it holds: upper, lower)"),
            "{e}"
        );
        let hostile = fixtures.join("hostile_system.pkl");
        let e = read_capture_frame(&hostile, None).unwrap_err().to_string();
        assert!(e.contains("calls os.system"), "{e}");
    }

    #[test]
    fn another_topology_of_the_same_surface_scores_near_zero_and_a_shift_scores_its_size() {
        let coarse = sheet(8, 1.0);
        let mut fine = sheet(8, 1.0);
        garments::subdivide(&mut fine);
        let lifted = sheet(13, 1.01);
        // A body far below, so nothing is inside it.
        let body_vertices = [
            [0.0, -5.0, 0.0],
            [1.0, -5.0, 0.0],
            [0.0, -5.0, 1.0],
            [0.0, -6.0, 0.0],
        ];
        let body = BodySurface {
            vertices: &body_vertices,
            triangles: &[[0, 2, 1], [0, 1, 3], [0, 3, 2], [1, 2, 3]],
        };
        let scorer = Scorer::new(&coarse.positions, &coarse.triangles, 0).with_samples(20_000);
        let same = score_frame(
            &scorer,
            &coarse.positions,
            &fine.positions,
            &fine.triangles,
            &body,
            0,
        );
        assert!(same.E_CD_cm < 0.5, "{same:?}");
        assert!(same.E_n < 1e-9, "{same:?}");
        let shifted = score_frame(
            &scorer,
            &coarse.positions,
            &lifted.positions,
            &lifted.triangles,
            &body,
            0,
        );
        // Sampling alone leaves a floor (about half the samples' spacing).
        assert!((1.0..1.3).contains(&shifted.E_CD_cm), "{shifted:?}");
        assert!(shifted.E_CD_cm > same.E_CD_cm + 0.5, "{shifted:?} {same:?}");
        assert!(shifted.distance_p90_cm >= 1.0 - 1e-9, "{shifted:?}");
        assert!(shifted.E_CD > same.E_CD);
        assert!(
            shifted.E_c.is_finite() && shifted.E_c_vertex == 0.0,
            "{shifted:?}"
        );
    }
}
