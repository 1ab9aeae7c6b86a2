//! A recording scored against another (the ground truth) with the paper's metrics, every 5th
//! frame: shared by `compare` and `demo`.

use std::path::Path;

use anyhow::{Result, bail};
use motions::BodyModel;
use sim::metrics::{BodySurface, FRAME_STRIDE, Scorer, Scores, jitter};
use sim::recording::Recording;

/// B scored against A: the mean of every 5th frame, each frame's scores, and both jitters.
pub struct Compared {
    pub mean: Scores,
    pub per_frame: Vec<(usize, Scores)>,
    /// Frames both recordings have.
    pub frames: usize,
    /// Mean |second difference| of vertex positions over all frames, cm.
    pub jitter_a: f64,
    pub jitter_b: f64,
}

/// Scores recording `b` against recording `a` (ground truth, same template) with the body of
/// `model` (E_c), every 5th frame.
pub fn score(a_path: &Path, b_path: &Path, model: &BodyModel, seed: u64) -> Result<Compared> {
    let a = Recording::read(a_path)?;
    let b = Recording::read(b_path)?;
    if a.template.triangles != b.template.triangles {
        bail!(
            "{} and {} do not share a garment template ({} vs {} triangles, or a different order)",
            a_path.display(),
            b_path.display(),
            a.template.triangles.len(),
            b.template.triangles.len()
        );
    }
    let frames = a.garment.len().min(b.garment.len());
    if frames == 0 {
        bail!(
            "no frames to score: {} has {}, {} has {}",
            a_path.display(),
            a.garment.len(),
            b_path.display(),
            b.garment.len()
        );
    }
    let scorer = Scorer::new(&a.template.positions, &a.template.triangles, seed);
    let to64 =
        |f: &[[f32; 3]]| -> Vec<[f64; 3]> { f.iter().map(|p| p.map(|c| c as f64)).collect() };
    let mut per_frame = Vec::new();
    for k in (0..frames).step_by(FRAME_STRIDE) {
        let body = a.body_at(model, k, a_path)?;
        let surface = BodySurface {
            vertices: &body.vertices,
            triangles: &body.faces,
        };
        let s = scorer.frame(
            &to64(&b.garment[k]),
            &to64(&a.garment[k]),
            Some(&surface),
            k,
        );
        per_frame.push((k, s));
    }
    let mean = Scores::mean(&per_frame.iter().map(|(_, s)| *s).collect::<Vec<_>>());
    let all = |r: &Recording| -> Vec<Vec<[f64; 3]>> {
        r.garment[..frames].iter().map(|f| to64(f)).collect()
    };
    Ok(Compared {
        mean,
        per_frame,
        frames,
        jitter_a: jitter(&all(&a)),
        jitter_b: jitter(&all(&b)),
    })
}
