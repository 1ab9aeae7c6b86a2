//! A surrogate's prediction as the commands share it: the model folder `--model` names, and a
//! predicted sequence recorded through the engine's `SequenceWriter` (atomically, with the
//! model and sampler settings in the metadata), shared by `predict`, `demo` and `evaluate`.

use std::ops::Range;
use std::path::{Path, PathBuf};

use anyhow::{Context, Result, bail};
use indicatif::{ProgressBar, ProgressDrawTarget, ProgressStyle};
use serde::Serialize;
use serde_json::json;
use sim::metrics::{BodySurface, FRAME_STRIDE, Scorer};
use sim::recording::{Channels, FrameRecord, SequenceMeta, SequenceWriter, TemplateArrays};
use sim::scene::FPS;
use surrogate::predict::{BodySequence, Predictor, PreparedGarment, Settings, Timing};
use surrogate::train::TrainedModel;

use crate::output::write_atomic;
use sim::run::Prepared;

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
    /// Deepest vertex and most vertices inside the body of any frame, when tested.
    pub max_penetration_m: Option<f64>,
    pub max_inside: Option<usize>,
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
                if let (Some(deepest), Some(n)) = (frame.max_penetration_m, frame.inside) {
                    stats.max_penetration_m =
                        Some(stats.max_penetration_m.unwrap_or(0.0).max(deepest));
                    stats.max_inside = Some(stats.max_inside.unwrap_or(0).max(n));
                }
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

/// A prepared scene to predict: the model, the sampler and where the recording goes.
pub struct SceneRequest<'a> {
    pub trained: &'a TrainedModel,
    /// The model as the recording's metadata names it (its folder).
    pub model_name: &'a str,
    pub settings: &'a Settings,
    pub out: &'a Path,
    pub obj_dir: Option<&'a Path>,
    pub body_vertices: bool,
    pub quiet: bool,
    /// The recording's `software` entry.
    pub software: &'a str,
}

/// What predicting a scene measured.
pub struct ScenePrediction {
    pub frames: usize,
    pub vertices: usize,
    /// Whether the model was trained on this template.
    pub seen: bool,
    pub stats: PredictionStats,
    /// Frames over the sampling's wall time (the template's preparation excluded).
    pub frames_per_s: f64,
    /// Preparing the template (atlas, position map, skinning) and the body sequence, s.
    pub garment_s: f64,
    /// Mean E_c and E_c_vertex of every 5th frame, %.
    pub e_c: f64,
    pub e_c_vertex: f64,
}

/// Predicts every frame of a prepared scene (the body poses and shapes the engine would
/// simulate) and records it, with a progress bar unless `quiet`.
pub fn predict_scene(prepared: &Prepared, r: &SceneRequest) -> Result<ScenePrediction> {
    let started = std::time::Instant::now();
    let (model, garment, scene) = (&prepared.model, &prepared.garment, &prepared.scene);
    let predictor = Predictor::new(r.trained, model)?;
    let template = TemplateArrays {
        positions: garment.positions.clone(),
        triangles: garment.triangles.clone(),
        uvs: garment.uvs.clone(),
        uv_triangles: garment.uv_triangles.clone(),
    };
    let mut ready = predictor
        .garment(&template)
        .with_context(|| format!("garment '{}'", garment.name))?;
    let motion = scene.body_motion();
    let frames = scene.num_frames();
    let betas: Vec<Vec<f64>> = (0..frames).map(|k| scene.frame_betas(k)).collect();
    let garment_s = started.elapsed().as_secs_f64();
    let seen = r
        .trained
        .data
        .templates
        .iter()
        .any(|t| t.name == garment.name && t.in_training());
    let predicted = json!({
        "model": r.model_name, "target": r.trained.data.target.name(),
        "resolution": r.trained.data.resolution, "settings": r.settings,
        "template_seen_in_training": seen,
    });
    let meta = scene.sequence_meta(&garment.name, model.name(), r.software);
    let bar = ProgressBar::new(frames as u64).with_style(
        ProgressStyle::with_template(
            "predicting [{bar:30}] {pos}/{len} frames ({per_sec}, eta {eta})",
        )?
        .progress_chars("=> "),
    );
    if r.quiet {
        bar.set_draw_target(ProgressDrawTarget::hidden());
    }
    let recorded = Recorded {
        predictor: &predictor,
        garment: &mut ready,
        template: &template,
        body: BodySequence {
            motion: &motion,
            betas: &betas,
            material: scene.config.material,
        },
        frames: 0..frames,
        settings: r.settings,
        meta: &meta,
        predicted: &predicted,
        faces: model.faces(),
        body_vertices: r.body_vertices,
        obj: r.obj_dir.map(|d| (d, garment.as_ref())),
        bar: &bar,
    };
    let stats = record_prediction(r.out, recorded)
        .with_context(|| format!("predicting into {}", r.out.display()))?;
    bar.finish_and_clear();
    let mean = |f: fn(&(f64, f64)) -> f64| -> f64 {
        stats.collision.iter().map(f).sum::<f64>() / stats.collision.len().max(1) as f64
    };
    Ok(ScenePrediction {
        frames,
        vertices: ready.vertices(),
        seen,
        frames_per_s: frames as f64 / stats.timing.wall_s.max(1e-9),
        garment_s,
        e_c: mean(|c| c.0),
        e_c_vertex: mean(|c| c.1),
        stats,
    })
}
