//! A surrogate's prediction as the commands share it: the model folder `--model` names, and a
//! predicted sequence recorded through the engine's `SequenceWriter` (atomically, with the
//! model and sampler settings in the metadata), shared by `predict` and `evaluate`.

use std::ops::Range;
use std::path::{Path, PathBuf};

use anyhow::{Result, bail};
use indicatif::ProgressBar;
use serde::Serialize;
use sim::metrics::{BodySurface, FRAME_STRIDE, Scorer};
use sim::recording::{Channels, FrameRecord, SequenceMeta, SequenceWriter, TemplateArrays};
use sim::scene::FPS;
use surrogate::predict::{BodySequence, Predictor, PreparedGarment, Settings, Timing};

use crate::output::write_atomic;
use crate::run::write_objs;

/// Where `--model builtin` looks: the weights shipped in the repository.
pub fn builtin_dir() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("surrogate/weights")
}

/// The run folder `--model` names (`builtin` or a folder).
pub fn model_dir(name: &str) -> Result<PathBuf> {
    if name == "builtin" {
        let dir = builtin_dir();
        if !dir.join("model.safetensors").is_file() {
            bail!(
                "no built-in model: {} holds no model.safetensors (this build ships none); \
                 train one (`dit-garment train`) and pass --model RUN",
                dir.display()
            );
        }
        return Ok(dir);
    }
    let dir = PathBuf::from(name);
    if !dir.is_dir() {
        bail!("--model {name}: not a run folder (or `builtin`)");
    }
    Ok(dir)
}

/// The recording's metadata: a garment sequence's, plus what made the prediction.
#[derive(Serialize)]
struct PredictedMeta<'a> {
    #[serde(flatten)]
    sequence: &'a SequenceMeta,
    predicted: &'a serde_json::Value,
}

/// What to predict and how to record it.
pub struct Recorded<'a> {
    /// The predictor and the template made ready for it.
    pub predictor: &'a Predictor<'a>,
    pub garment: &'a mut PreparedGarment,
    /// The template arrays written to the recording.
    pub template: &'a TemplateArrays,
    pub body: BodySequence<'a>,
    pub frames: Range<usize>,
    pub settings: &'a Settings,
    /// The sequence's metadata and the `predicted` object added to it.
    pub meta: &'a SequenceMeta,
    pub predicted: &'a serde_json::Value,
    /// Body triangles; recorded with the body vertices when `body_vertices`.
    pub faces: &'a [[u32; 3]],
    pub body_vertices: bool,
    /// OBJ frames of this garment into this folder.
    pub obj: Option<(&'a Path, &'a garments::Garment)>,
    pub bar: &'a ProgressBar,
}

/// What a recorded prediction measured.
#[derive(Debug, Default)]
pub struct PredictionStats {
    pub finite: bool,
    pub max_penetration_m: f64,
    pub max_inside: usize,
    pub pushed: usize,
    /// (E_c, E_c_vertex) of every 5th frame, %.
    pub collision: Vec<(f64, f64)>,
    pub timing: Timing,
}

/// Predicts and records into `out` (atomically).
pub fn record_prediction(out: &Path, r: Recorded) -> Result<PredictionStats> {
    let scorer = Scorer::new(&r.template.positions, &r.template.triangles, 0);
    let mut stats = PredictionStats {
        finite: true,
        ..PredictionStats::default()
    };
    let meta = PredictedMeta {
        sequence: r.meta,
        predicted: r.predicted,
    };
    let motion = r.body.motion;
    write_atomic(out, |w| {
        let channels = Channels {
            template: Some(r.template),
            body_faces: r.body_vertices.then_some(r.faces),
            joints: false,
            stats: false,
        };
        let mut rec = SequenceWriter::new(w, &meta, channels, FPS)?;
        stats.timing = r.predictor.predict(
            r.garment,
            &r.body,
            r.frames.clone(),
            r.settings,
            &mut |frame| {
                let k = frame.index;
                stats.finite &= frame.garment.iter().flatten().all(|v| v.is_finite());
                stats.max_penetration_m = stats.max_penetration_m.max(frame.max_penetration_m);
                stats.max_inside = stats.max_inside.max(frame.inside);
                stats.pushed += frame.pushed;
                if k % FRAME_STRIDE == 0 {
                    let surface = BodySurface {
                        vertices: &frame.body,
                        triangles: r.faces,
                    };
                    stats
                        .collision
                        .push(scorer.collision(&frame.garment, &surface, k));
                }
                let record = FrameRecord {
                    index: k,
                    garment: Some(&frame.garment),
                    pose: &motion.frames[k].pose,
                    transl: motion.frames[k].transl,
                    betas: &r.body.betas[k],
                    body_vertices: r.body_vertices.then_some(frame.body.as_slice()),
                    joints: None,
                    stats: None,
                };
                rec.write_frame(&record).map_err(surrogate::Error::from)?;
                if let Some((dir, garment)) = r.obj {
                    write_objs(dir, k, garment, &frame.garment, &frame.body, r.faces)
                        .map_err(|e| surrogate::Error::Invalid(format!("{e:#}")))?;
                }
                r.bar.inc(1);
                Ok(())
            },
        )?;
        rec.finish()?;
        Ok(())
    })?;
    Ok(stats)
}
