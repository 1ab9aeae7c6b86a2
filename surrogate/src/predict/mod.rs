//! Direct posing with a trained model: for every frame of a body sequence, the garment sampled
//! from noise given the template's position map, the body shape, the pose window and the
//! material, with intersection guidance (`guidance.rs`), decoded through the chart-aware
//! readback to world vertices.
//!
//! Frames are independent (the paper's model), so a sequence is sampled in batches of frames
//! (`sampling.rs`); a model that takes the garment's previous state (`previous_state`) is
//! sampled one frame after another instead, each frame given the model's own map of the frame
//! before. By default every frame starts from the same noise, which keeps neighbouring frames
//! coherent; [`Noise::PerFrame`] draws it per frame. Same inputs and settings, same bits.

mod guidance;
mod record;
mod sampling;

pub use guidance::{
    CONTACT_BAND_M, Clearance, ClearanceCache, Guidance, REUSE_WITHIN_M, clearances,
    penalty_gradient, penetration, push_out,
};
pub use record::{
    PredictionStats, Recorded, SceneInput, ScenePrediction, SceneRequest, predict_scene,
    record_prediction,
};

use std::time::Instant;

use motions::{BodyModel, Motion, ShapedBody};
use rayon::prelude::*;
use serde::{Deserialize, Serialize};
use sim::Material;
use sim::obstacles::MeshSurface;
use sim::recording::TemplateArrays;

use crate::data::{ConditionLayout, body_input_maps, channels_first, previous_state_map};
use crate::error::{Error, Result, bad_value};
use crate::geometry::{FrameBase, FrameBody, GeometryImage, Targets};
use crate::run::{Objective, TrainedModel};

/// Euler steps by default (chosen from the steps sweep in docs/SURROGATE.md).
pub const DEFAULT_STEPS: usize = 4;

/// Guidance passes after a regression model's one step (measured: docs/SURROGATE.md).
pub const REGRESSION_REFINE: usize = 2;

/// The random stream of the sampler's initial noise.
pub const NOISE_STREAM: u64 = 3;
/// Draw d > 0 of a K-draw mean takes its noise from stream `EXTRA_DRAW_STREAMS + d`.
pub const EXTRA_DRAW_STREAMS: u64 = 100;

/// Where the frames' initial noise comes from.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum Noise {
    /// One noise image for every frame of the sequence (temporal coherence).
    #[default]
    Shared,
    /// A noise image per frame.
    PerFrame,
}

/// How a sequence is sampled.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct Settings {
    /// Euler steps from noise to data.
    pub steps: usize,
    /// Time shift of the schedule (1: uniform).
    pub shift: f64,
    /// Intersection guidance.
    pub guidance: Guidance,
    /// Seed of the initial noise.
    pub seed: u64,
    /// Frames sampled together.
    pub batch: usize,
    /// Shared or per-frame initial noise.
    pub noise: Noise,
    /// Samples drawn per frame (each from its own noise) and averaged: the mean of K draws
    /// approaches the conditional mean, which is what minimizes E_v.
    pub draws: usize,
    /// Push the vertices still inside the body out after sampling (off by default; its
    /// effect is reported apart from the model's).
    pub resolve_penetration: bool,
    /// Test every predicted vertex against the body after sampling (the frames' `inside` and
    /// `max_penetration_m`); off, an unguided prediction never builds a body surface.
    pub inside_test: bool,
}

impl Default for Settings {
    fn default() -> Self {
        Self {
            steps: DEFAULT_STEPS,
            shift: 1.0,
            guidance: Guidance::default(),
            seed: 0,
            batch: 16,
            noise: Noise::Shared,
            draws: 1,
            resolve_penetration: false,
            inside_test: true,
        }
    }
}

impl Settings {
    /// The defaults for `trained`: a regression model (trained at s = 1 only) is sampled in
    /// one step, guided on that step and refined by [`REGRESSION_REFINE`] guidance passes; a flow model in [`DEFAULT_STEPS`], guided over the
    /// second half (docs/SURROGATE.md, the model card).
    pub fn for_model(trained: &TrainedModel) -> Self {
        let defaults = Self::default();
        match trained.config.training.objective {
            Objective::Regression => Self {
                steps: 1,
                guidance: Guidance {
                    start: 0.0,
                    refine: REGRESSION_REFINE,
                    ..defaults.guidance
                },
                ..defaults
            },
            Objective::Flow => defaults,
        }
    }

    /// Checks the values, naming the first bad one.
    pub fn validate(&self) -> Result<()> {
        if !(1..=1000).contains(&self.steps) {
            return Err(bad_value("steps", self.steps, "1 to 1000"));
        }
        if !(self.shift.is_finite() && self.shift > 0.0 && self.shift <= 100.0) {
            return Err(bad_value("shift", self.shift, "a number in (0, 100]"));
        }
        if !(1..=64).contains(&self.draws) {
            return Err(bad_value("draws", self.draws, "1 to 64"));
        }
        if !(1..=4096).contains(&self.batch) {
            return Err(bad_value("batch", self.batch, "1 to 4096 frames"));
        }
        self.guidance.validate()
    }
}

/// A body sequence to dress: the poses the body follows (blend-in included), its shape per
/// frame and the cloth's material.
#[derive(Debug, Clone, Copy)]
pub struct BodySequence<'a> {
    /// Poses and root translations.
    pub motion: &'a Motion,
    /// Body shape of every frame.
    pub betas: &'a [Vec<f64>],
    /// The cloth's material.
    pub material: Material,
}

/// One predicted frame.
#[derive(Debug, Clone)]
pub struct PredictedFrame {
    /// Frame index.
    pub index: usize,
    /// Garment vertices, m (after the push-out when it is on).
    pub garment: Vec<[f64; 3]>,
    /// Posed body vertices, m.
    pub body: Vec<[f64; 3]>,
    /// Vertices inside the body as sampled (before any push-out), when tested.
    pub inside: Option<usize>,
    /// Deepest vertex inside the body as sampled, m, when tested.
    pub max_penetration_m: Option<f64>,
    /// Vertices the push-out moved.
    pub pushed: usize,
}

/// Where a prediction's time went, s: the wall time of the sampling (the frames' hand-over
/// excluded), then per part summed over the batches sampled at once (so the parts may add up
/// to more than the wall time).
#[derive(Debug, Clone, Copy, Default, PartialEq, Serialize, Deserialize)]
pub struct Timing {
    /// Wall time.
    pub wall_s: f64,
    /// The network's forward passes.
    pub network_s: f64,
    /// Guidance: decoding, body queries, gradients.
    pub guidance_s: f64,
    /// Conditions, bodies, noise, the final decode and the push-out.
    pub other_s: f64,
}

impl Timing {
    /// Adds a batch's parts (not its wall time, which overlaps the others').
    fn add(&mut self, batch: &Timing) {
        self.network_s += batch.network_s;
        self.guidance_s += batch.guidance_s;
        self.other_s += batch.other_s;
    }
}

/// A template made ready for a model: its geometry image at the model's resolution, its
/// targets, and the network's fixed inputs.
pub struct PreparedGarment {
    image: GeometryImage,
    targets: Targets,
    /// Normalized position map, `[3, R, R]` flat.
    position: Vec<f32>,
    /// Loss mask, `[R, R]` flat.
    mask: Vec<f32>,
    /// Per texel, 1 over the sum of the readback weights that read it (0 if unread): spreads
    /// a per-vertex gradient so that reading it back returns about the same values.
    spread: Vec<f64>,
    triangles: Vec<[u32; 3]>,
}

impl PreparedGarment {
    /// Vertices of the template.
    pub fn vertices(&self) -> usize {
        self.image.vertices()
    }

    /// The template's triangles.
    pub fn triangles(&self) -> &[[u32; 3]] {
        &self.triangles
    }
}

/// What the network is given for a set of frames (normalized, channels first).
#[derive(Debug, Clone, PartialEq)]
pub struct NetworkInputs {
    /// Texel inputs `[F, P, R, R]`: the position map, then the body inputs when the model
    /// takes them.
    pub texels: Vec<f32>,
    /// Condition vectors `[F, D]`.
    pub conditions: Vec<f32>,
}

/// A trained model on a body model.
pub struct Predictor<'a> {
    trained: &'a TrainedModel,
    body: &'a BodyModel,
    layout: ConditionLayout,
}

/// The posed bodies of frames, shaping only when the shape changes.
fn posed_bodies(
    model: &BodyModel,
    seq: &BodySequence,
    frames: &[usize],
) -> Result<Vec<Vec<[f64; 3]>>> {
    let mut shaped: Option<ShapedBody> = None;
    frames
        .iter()
        .map(|&k| {
            if shaped.as_ref().is_none_or(|s| s.betas != seq.betas[k]) {
                shaped = Some(model.shape(&seq.betas[k])?);
            }
            let s = shaped.as_ref().expect("set above");
            Ok(model.pose(s, &seq.motion.frames[k])?.vertices)
        })
        .collect()
}

impl<'a> Predictor<'a> {
    /// A predictor of `trained` on `body`, which must be the body model it was trained on.
    pub fn new(trained: &'a TrainedModel, body: &'a BodyModel) -> Result<Self> {
        let data = &trained.data;
        if data.body_model != body.name() {
            return Err(Error::ModelMismatch {
                run: trained.run.display().to_string(),
                problem: format!(
                    "trained on the body model '{}', not '{}'",
                    data.body_model,
                    body.name()
                ),
            });
        }
        let layout = data.condition_layout(body.num_betas());
        let same_blocks = layout
            .blocks()
            .iter()
            .zip(&data.condition)
            .all(|(a, b)| (&a.name, a.offset, a.size) == (&b.name, b.offset, b.size));
        if layout.dim() != data.condition_dim || !same_blocks {
            return Err(Error::ModelMismatch {
                run: trained.run.display().to_string(),
                problem: format!(
                    "takes {} condition values; '{}' with a window of {} gives {}",
                    data.condition_dim,
                    body.name(),
                    data.window,
                    layout.dim()
                ),
            });
        }
        Ok(Self {
            trained,
            body,
            layout,
        })
    }

    /// Frames of pose history a frame's condition holds.
    pub fn window(&self) -> usize {
        self.layout.window
    }

    /// Prepares a template (rest positions on the canonical body, with UVs): its atlas and
    /// position map are made here, so a template the model never saw is the normal case.
    pub fn garment(&self, template: &TemplateArrays) -> Result<PreparedGarment> {
        if template.uvs.is_empty() || template.uv_triangles.len() != template.triangles.len() {
            return Err(Error::NoUvs);
        }
        let data = &self.trained.data;
        let image = GeometryImage::of_template(template, data.resolution)?;
        let targets = Targets::new(
            self.body,
            &template.positions,
            &template.triangles,
            data.target,
            data.root,
        )?;
        let mut position = channels_first(&image.encode(&template.positions)?);
        data.normalization
            .position_maps
            .normalize(&mut position, image.resolution().pow(2));
        let mask = image.loss_mask().iter().map(|&m| m as u8 as f32).collect();
        let weights = image.read_transpose(&vec![[1.0; 3]; image.vertices()])?;
        let spread = weights
            .iter()
            .map(|w| if w[0] > 1e-12 { 1.0 / w[0] } else { 0.0 })
            .collect();
        Ok(PreparedGarment {
            image,
            targets,
            position,
            mask,
            spread,
            triangles: template.triangles.clone(),
        })
    }

    /// Predicts `frames` of `seq`, handing each to `on_frame` in order. Batches
    /// are sampled on all of rayon's threads at once, one batch per thread: the network's
    /// operations are too small to use a second core on their own (docs/BENCHMARKS.md).
    pub fn predict(
        &self,
        garment: &mut PreparedGarment,
        seq: &BodySequence,
        frames: std::ops::Range<usize>,
        settings: &Settings,
        on_frame: &mut dyn FnMut(&PredictedFrame) -> Result<()>,
    ) -> Result<Timing> {
        settings.validate()?;
        let motion = seq.motion;
        let window = self.layout.window;
        if motion.len() <= window {
            return Err(Error::MotionTooShort {
                motion: motion.name.clone(),
                frames: motion.len(),
                needed: window + 1,
            });
        }
        if frames.end > motion.len() || frames.end > seq.betas.len() {
            return Err(Error::FramesOutOfRange {
                end: frames.end,
                len: motion.len().min(seq.betas.len()),
            });
        }
        if self.trained.config.model.previous_state {
            return self.predict_in_turn(garment, seq, frames, settings, on_frame);
        }
        let lanes = rayon::current_num_threads().max(1);
        let mut timing = Timing::default();
        let all: Vec<usize> = frames.collect();
        // Each lane keeps its frames' body surfaces and refits them to the next batch's
        // bodies instead of building them again.
        let mut pools: Vec<Vec<MeshSurface>> = (0..lanes).map(|_| Vec::new()).collect();
        let garment: &PreparedGarment = garment;
        for round in all.chunks(settings.batch * lanes) {
            let started = Instant::now();
            // A short last round is shared evenly, not left to the first lanes while the
            // others wait.
            let results = round
                .chunks(round.len().div_ceil(lanes))
                .zip(pools.iter_mut())
                .collect::<Vec<_>>()
                .into_par_iter()
                .map(|(chunk, pool)| self.sample_batch(garment, seq, chunk, pool, settings, None))
                .collect::<Result<Vec<_>>>()?;
            timing.wall_s += started.elapsed().as_secs_f64();
            for (frames, t, _) in results {
                timing.add(&t);
                frames.iter().try_for_each(|f| hand_over(f, on_frame))?;
            }
        }
        Ok(timing)
    }

    /// [`Self::predict`] for a model that takes the garment's previous state: one frame after
    /// another, each given the map the model made for the frame before (the first frame of
    /// `frames` is given none, as the first frame of a sequence is in training).
    fn predict_in_turn(
        &self,
        garment: &PreparedGarment,
        seq: &BodySequence,
        frames: std::ops::Range<usize>,
        settings: &Settings,
        on_frame: &mut dyn FnMut(&PredictedFrame) -> Result<()>,
    ) -> Result<Timing> {
        let mut timing = Timing::default();
        let mut surfaces = Vec::new();
        let mut previous: Option<Vec<f32>> = None;
        for k in frames {
            let started = Instant::now();
            let (predicted, t, map) = self.sample_batch(
                garment,
                seq,
                &[k],
                &mut surfaces,
                settings,
                previous.as_deref(),
            )?;
            timing.wall_s += started.elapsed().as_secs_f64();
            timing.add(&t);
            predicted.iter().try_for_each(|f| hand_over(f, on_frame))?;
            previous = Some(map);
        }
        Ok(timing)
    }

    /// The network's inputs for `frames` of `seq`, normalized as in training: what the tensors
    /// of a recorded sequence hold for the same frames (tested). A previous-state model is
    /// given no previous state for any of them (as the first frame of a sequence).
    pub fn network_inputs(
        &self,
        garment: &PreparedGarment,
        seq: &BodySequence,
        frames: &[usize],
    ) -> Result<NetworkInputs> {
        let mut targets = garment.targets.clone();
        let mut surfaces = Vec::new();
        if self.trained.config.model.body_nearest {
            let posed = posed_bodies(self.body, seq, frames)?;
            self.refit(&posed, frames, &mut surfaces)?;
        }
        Ok(self
            .inputs_of(garment, &mut targets, seq, frames, &surfaces, None)?
            .1)
    }

    /// Fits `surfaces` (grown as needed) to the posed bodies of `frames`, one each.
    fn refit(
        &self,
        posed: &[Vec<[f64; 3]>],
        frames: &[usize],
        surfaces: &mut Vec<MeshSurface>,
    ) -> Result<()> {
        for (i, (vertices, k)) in posed.iter().zip(frames).enumerate() {
            let v: Vec<sim::Vec3> = vertices.iter().map(|p| sim::Vec3::from(*p)).collect();
            match surfaces.get_mut(i) {
                Some(surface) => surface.update(&v, &vec![sim::Vec3::zeros(); v.len()]),
                None => surfaces.push(MeshSurface::new(
                    &format!("body of frame {k}"),
                    &v,
                    self.body.faces(),
                )?),
            }
        }
        Ok(())
    }

    /// The frames' bases and network inputs; `surfaces` are the frames' posed bodies when the
    /// model takes the nearest-body inputs; `previous` is the normalized map before the first
    /// frame when the model takes the previous state (then `frames` holds one frame).
    fn inputs_of(
        &self,
        garment: &PreparedGarment,
        targets: &mut Targets,
        seq: &BodySequence,
        frames: &[usize],
        surfaces: &[MeshSurface],
        previous: Option<&[f32]>,
    ) -> Result<(Vec<FrameBase>, NetworkInputs)> {
        let data = &self.trained.data;
        let plane = data.resolution.pow(2);
        let model = &self.trained.config.model;
        let body_of = |k: usize| FrameBody {
            pose: &seq.motion.frames[k],
            betas: &seq.betas[k],
        };
        let bases = frames
            .iter()
            .map(|&k| targets.frame_base(self.body, body_of(k)))
            .collect::<Result<Vec<FrameBase>>>()?;
        let stats = &data.normalization;
        let mut inputs = NetworkInputs {
            texels: Vec::with_capacity(frames.len() * model.texel_channels() * plane),
            conditions: Vec::with_capacity(frames.len() * data.condition_dim),
        };
        for (i, &k) in frames.iter().enumerate() {
            inputs.texels.extend_from_slice(&garment.position);
            if model.body_inputs {
                let bodies = stats.bodies.as_ref().ok_or_else(|| Error::ModelMismatch {
                    run: self.trained.run.display().to_string(),
                    problem: "takes body inputs; its tensors.json has no statistics for them"
                        .into(),
                })?;
                let before = body_of(k.saturating_sub(1));
                let nearest = model.body_nearest.then(|| &surfaces[i]);
                let mut maps = body_input_maps(
                    targets,
                    &garment.image,
                    self.body,
                    body_of(k),
                    before,
                    nearest,
                )?;
                bodies.normalize(&mut maps, plane);
                inputs.texels.extend(maps);
            }
            if model.previous_state {
                inputs
                    .texels
                    .extend(previous_state_map(previous, &garment.mask, &stats.targets));
            }
            let c = self
                .layout
                .vector(seq.motion, k, &seq.betas[k], &seq.material)?;
            let mut c: Vec<f32> = c.iter().map(|&x| x as f32).collect();
            stats.conditions.normalize(&mut c, 1);
            inputs.conditions.extend(c);
        }
        Ok((bases, inputs))
    }
}

/// Hands a frame on, unless it holds a non-finite vertex: finite weights and statistics can
/// still overflow (a condition far outside training), and non-finite cloth is never handed on
/// as a prediction.
fn hand_over(
    frame: &PredictedFrame,
    on_frame: &mut dyn FnMut(&PredictedFrame) -> Result<()>,
) -> Result<()> {
    if !frame.garment.iter().flatten().all(|v| v.is_finite()) {
        return Err(Error::NonFinitePrediction { frame: frame.index });
    }
    on_frame(frame)
}
