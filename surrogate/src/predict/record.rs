//! A prediction recorded: every frame the predictor makes written through the engine's
//! `SequenceWriter` (atomically, with the model and sampler settings in the metadata), its
//! collisions scored on the way, and optionally OBJ frames. `predict`, `demo` and the
//! evaluation's report pictures record predictions this way.

use std::ops::Range;
use std::path::Path;

use serde::Serialize;
use serde_json::json;
use sim::metrics::{BodySurface, FRAME_STRIDE, Scorer};
use sim::recording::{Channels, FrameRecord, SequenceMeta, SequenceWriter, TemplateArrays};
use sim::scene::FPS;

use super::{BodySequence, Predictor, PreparedGarment, Settings, Timing};
use crate::error::{Error, Result};
use crate::run::TrainedModel;

/// The recording's metadata: a garment sequence's, plus what made the prediction.
#[derive(Serialize)]
struct PredictedMeta<'a> {
    #[serde(flatten)]
    sequence: &'a SequenceMeta,
    predicted: &'a serde_json::Value,
}

/// What to predict and how to record it.
pub struct Recorded<'a> {
    /// The predictor.
    pub predictor: &'a Predictor<'a>,
    /// The template made ready for it.
    pub garment: &'a mut PreparedGarment,
    /// The template arrays written to the recording.
    pub template: &'a TemplateArrays,
    /// The body's motion, shapes and the material.
    pub body: BodySequence<'a>,
    /// The frames predicted.
    pub frames: Range<usize>,
    /// The sampler's settings.
    pub settings: &'a Settings,
    /// The sequence's metadata.
    pub meta: &'a SequenceMeta,
    /// What made the prediction, added to the metadata as `predicted`.
    pub predicted: &'a serde_json::Value,
    /// Body triangles (the collision scores', and recorded with the body vertices).
    pub faces: &'a [[u32; 3]],
    /// Whether the body vertices are recorded.
    pub body_vertices: bool,
    /// OBJ frames of this garment into this folder.
    pub obj: Option<(&'a Path, &'a garments::Garment)>,
    /// Called after each frame is written.
    pub tick: &'a mut dyn FnMut(),
}

/// What a recorded prediction measured.
#[derive(Debug, Default)]
pub struct PredictionStats {
    /// Whether every vertex of every frame is finite.
    pub finite: bool,
    /// Deepest vertex inside the body of any frame, m, when tested.
    pub max_penetration_m: Option<f64>,
    /// Most vertices inside the body of any frame, when tested.
    pub max_inside: Option<usize>,
    /// Vertices pushed out of the body, all frames.
    pub pushed: usize,
    /// (E_c, E_c_vertex) of every 5th frame, %.
    pub collision: Vec<(f64, f64)>,
    /// Where the sampling's time went.
    pub timing: Timing,
}

/// Predicts and records into `out` (atomically: nothing there unless every frame was made).
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
    let tick = r.tick;
    files::write_fallible(out, |w| {
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
                rec.write_frame(&record)?;
                if let Some((dir, garment)) = r.obj {
                    let (cloth, body) = (&frame.garment, &frame.body);
                    sim::run::write_objs(dir, k, garment, cloth, body, r.faces)?;
                }
                tick();
                Ok(())
            },
        )?;
        rec.finish()?;
        Ok::<(), Error>(())
    })?;
    Ok(stats)
}

/// A prepared scene to predict: the model, the sampler and where the recording goes.
pub struct SceneRequest<'a> {
    /// The model.
    pub trained: &'a TrainedModel,
    /// The model as the recording's metadata names it (its folder).
    pub model_name: &'a str,
    /// The sampler's settings.
    pub settings: &'a Settings,
    /// The recording.
    pub out: &'a Path,
    /// OBJ frames into this folder.
    pub obj_dir: Option<&'a Path>,
    /// Whether the body vertices are recorded.
    pub body_vertices: bool,
}

/// What predicting a scene measured.
pub struct ScenePrediction {
    /// Frames predicted.
    pub frames: usize,
    /// Garment vertices.
    pub vertices: usize,
    /// Whether the model was trained on this template.
    pub seen: bool,
    /// What the recorded prediction measured.
    pub stats: PredictionStats,
    /// Frames over the sampling's wall time (the template's preparation excluded).
    pub frames_per_s: f64,
    /// Preparing the template (atlas, position map, skinning) and the body sequence, s.
    pub garment_s: f64,
    /// Mean E_c of every 5th frame, %.
    pub e_c: f64,
    /// Mean E_c_vertex of every 5th frame, %.
    pub e_c_vertex: f64,
}

/// A scene to predict, as plain data: the body model, the garment template, and per frame the
/// body's pose (blend-in included) and shape, with the material and the recording's metadata.
/// The command line builds it from the scene the engine would simulate, so both see the same
/// bodies; the surrogate never runs the scene itself.
pub struct SceneInput<'a> {
    /// The body model the frames pose.
    pub body_model: &'a motions::BodyModel,
    /// The garment template.
    pub garment: &'a garments::Garment,
    /// The body's motion, every frame predicted.
    pub motion: motions::Motion,
    /// The body's shape values per frame.
    pub betas: Vec<Vec<f64>>,
    /// The cloth's material.
    pub material: sim::Material,
    /// The recording's metadata.
    pub meta: SequenceMeta,
}

impl<'a> SceneInput<'a> {
    /// What the engine would simulate of a prepared scene: its bodies (the blend-in included,
    /// the frame count the configuration asks), shape, material and metadata, as plain data
    /// (the command line's and the Python package's `predict`); `software` names the writer.
    pub fn of_scene(p: &'a sim::run::Prepared, software: &str) -> Self {
        let scene = &p.scene;
        let frames = scene.num_frames();
        let mut motion = scene.body_motion();
        motion.frames.truncate(frames);
        Self {
            body_model: &p.model,
            garment: &p.garment,
            motion,
            betas: (0..frames).map(|k| scene.frame_betas(k)).collect(),
            material: scene.config.material,
            meta: scene.sequence_meta(&p.garment.name, p.model.name(), software),
        }
    }
}

/// Predicts every frame of a scene and records it; `tick` is called after each frame.
pub fn predict_scene(
    input: &SceneInput,
    r: &SceneRequest,
    tick: &mut dyn FnMut(),
) -> Result<ScenePrediction> {
    let started = std::time::Instant::now();
    let (model, garment) = (input.body_model, input.garment);
    let predictor = Predictor::new(r.trained, model)?;
    let template = TemplateArrays::from(garment);
    let mut ready = predictor
        .garment(&template)
        .map_err(|e| Error::GarmentInput {
            garment: garment.name.clone(),
            source: Box::new(e),
        })?;
    let frames = input.betas.len().min(input.motion.len());
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
    let recorded = Recorded {
        predictor: &predictor,
        garment: &mut ready,
        template: &template,
        body: BodySequence {
            motion: &input.motion,
            betas: &input.betas,
            material: input.material,
        },
        frames: 0..frames,
        settings: r.settings,
        meta: &input.meta,
        predicted: &predicted,
        faces: model.faces(),
        body_vertices: r.body_vertices,
        obj: r.obj_dir.map(|d| (d, garment)),
        tick,
    };
    let stats = record_prediction(r.out, recorded)?;
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
