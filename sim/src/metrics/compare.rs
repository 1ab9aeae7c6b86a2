//! One recording scored against another (the ground truth, the same template) with the
//! paper's metrics every [`FRAME_STRIDE`]-th frame: what `compare` prints and the demo
//! reports of its prediction.

use std::path::Path;

use motions::BodyModel;

use super::{BodySurface, FRAME_STRIDE, P3, Scorer, Scores, jitter};
use crate::recording::Recording;
use crate::{Error, Result};

/// B scored against A: the mean of the scored frames, each scored frame, and both jitters.
#[derive(Debug, Clone)]
pub struct Compared {
    /// The mean over the scored frames.
    pub mean: Scores,
    /// Each scored frame with its index.
    pub per_frame: Vec<(usize, Scores)>,
    /// Frames both recordings have.
    pub frames: usize,
    /// A's jitter over all those frames, cm.
    pub jitter_a: f64,
    /// B's jitter, cm.
    pub jitter_b: f64,
}

/// Scores recording `b` against recording `a` with the body of `model` (E_c; posed from A's
/// recorded parameters when it carries no body vertices); `seed` draws the surface samples.
pub fn compare_recordings(
    a_path: &Path,
    b_path: &Path,
    model: &BodyModel,
    seed: u64,
) -> Result<Compared> {
    let a = Recording::read(a_path)?;
    let b = Recording::read(b_path)?;
    compare(&a, a_path, &b, b_path, model, seed)
}

/// [`compare_recordings`] of two recordings already read (the Python package's `metrics`);
/// `a_path` and `b_path` name them in errors.
pub fn compare(
    a: &Recording,
    a_path: &Path,
    b: &Recording,
    b_path: &Path,
    model: &BodyModel,
    seed: u64,
) -> Result<Compared> {
    let refuse = |message: String| Error::Recording {
        path: b_path.display().to_string(),
        message,
    };
    if a.template.triangles != b.template.triangles {
        return Err(refuse(format!(
            "does not share the garment template of {} ({} against {} triangles, or another \
             order)",
            a_path.display(),
            b.template.triangles.len(),
            a.template.triangles.len()
        )));
    }
    let frames = a.garment.len().min(b.garment.len());
    if frames == 0 {
        return Err(refuse(format!(
            "no frames to score: it has {}, {} has {}",
            b.garment.len(),
            a_path.display(),
            a.garment.len()
        )));
    }
    let scorer = Scorer::new(&a.template.positions, &a.template.triangles, seed);
    let to64 = |f: &[[f32; 3]]| -> Vec<P3> { f.iter().map(|p| p.map(f64::from)).collect() };
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
    let all =
        |r: &Recording| -> Vec<Vec<P3>> { r.garment[..frames].iter().map(|f| to64(f)).collect() };
    Ok(Compared {
        mean,
        per_frame,
        frames,
        jitter_a: jitter(&all(a)),
        jitter_b: jitter(&all(b)),
    })
}

#[cfg(test)]
mod tests {
    use std::sync::Arc;

    use super::*;
    use crate::run::Prepared;
    use crate::run::tests::skirt;

    #[test]
    fn scores_the_frames_both_have_and_refuses_another_template() {
        let dir = tempfile::tempdir().unwrap();
        let record = |name: &str, p: &Prepared| {
            let path = dir.path().join(name);
            p.record_file(&path, "test", None, |_| Ok(())).unwrap();
            path
        };
        let a = record("a.mcap", &skirt(7));
        // The same deterministic scene, shorter: its frames are A's first ones.
        let b = record("b.mcap", &skirt(4));
        let model = BodyModel::default_body();
        let same = compare_recordings(&a, &a, &model, 0).unwrap();
        assert_eq!((same.frames, same.per_frame.len()), (7, 2));
        assert_eq!(same.mean.E_v, 0.0);
        assert_eq!(same.jitter_a, same.jitter_b);
        assert!(same.mean.E_c.is_finite());
        let shorter = compare_recordings(&a, &b, &model, 0).unwrap();
        assert_eq!((shorter.frames, shorter.per_frame.len()), (4, 1));
        assert_eq!(shorter.mean.E_v, 0.0);
        // A finer skirt is another template.
        let p = skirt(3);
        let params = garments::SkirtParams {
            columns: 20,
            rings: 8,
            ..garments::SkirtParams::default()
        };
        let (garment, attachments) =
            crate::scene::builtin_template(&model, "skirt", &params).unwrap();
        let shaped = model.shape(&p.scene.config.betas).unwrap();
        let motion = motions::library::MotionSpec::parse("walk")
            .unwrap()
            .generate(&model, &shaped)
            .unwrap();
        let other = Prepared::new(
            p.model.clone(),
            Arc::new(garment),
            attachments,
            motion,
            p.scene.config.clone(),
        )
        .unwrap();
        let c = record("c.mcap", &other);
        let e = compare_recordings(&a, &c, &model, 0).unwrap_err();
        assert!(e.to_string().contains("garment template"), "{e}");
    }
}
