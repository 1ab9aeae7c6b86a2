//! One batch of frames through the sampler, as named stages over plain data: the bodies and
//! the network's inputs ([`Predictor::prepare_batch`]), the draws of the flow with guidance
//! on its steps ([`Batch::draw`]), the guidance passes on the sample ([`Batch::refine`]),
//! and the decode to world vertices with the inside test ([`Batch::finish`]).

use std::time::Instant;

use burn::prelude::*;
use sim::obstacles::MeshSurface;

use super::{
    BodySequence, ClearanceCache, EXTRA_DRAW_STREAMS, NOISE_STREAM, Noise, PredictedFrame,
    Predictor, PreparedGarment, Settings, Timing, penalty_gradient, penetration, posed_bodies,
    push_out,
};
use crate::data::Stats;
use crate::error::{Error, Result};
use crate::flow::{Conditioned, euler, time_grid};
use crate::geometry::FrameBase;
use crate::noise::{generator, normal};

/// A batch of frames between the stages: what every stage reads, and each frame's clearances
/// from its last body query (a refinement pass and the final inside test ask again only for
/// the vertices that moved).
struct Batch<'a> {
    garment: &'a PreparedGarment,
    chunk: &'a [usize],
    bases: Vec<FrameBase>,
    /// The frames' posed bodies.
    posed: Vec<Vec<[f64; 3]>>,
    /// Their surfaces, where guidance, the inside test or the nearest-body inputs need them.
    surfaces: &'a [MeshSurface],
    known: Vec<ClearanceCache>,
    targets: &'a Stats,
    resolution: usize,
    band: f64,
}

impl<'a> Predictor<'a> {
    /// Samples one batch of frames and decodes it; `surfaces` are body surfaces to refit
    /// (one per frame, grown as needed); `previous` as in [`Self::inputs_of`]. Also returns
    /// the sampled normalized maps `[B, 3, R, R]` (guidance included).
    pub(super) fn sample_batch(
        &self,
        garment: &PreparedGarment,
        seq: &BodySequence,
        chunk: &[usize],
        surfaces: &mut Vec<MeshSurface>,
        settings: &Settings,
        previous: Option<&[f32]>,
    ) -> Result<(Vec<PredictedFrame>, Timing, Vec<f32>)> {
        let mut timing = Timing::default();
        let started = Instant::now();
        let (mut batch, field) =
            self.prepare_batch(garment, seq, chunk, surfaces, settings, previous)?;
        timing.other_s += started.elapsed().as_secs_f64();

        let sampling = Instant::now();
        let mut values = vec![0.0f32; batch.values_len()];
        for d in 0..settings.draws {
            let draw = batch.draw(&field, d, settings, &mut timing)?;
            for (v, x) in values.iter_mut().zip(draw) {
                *v += x / settings.draws as f32;
            }
        }
        if settings.guidance.weight > 0.0 {
            batch.refine(&mut values, settings.guidance.refine, &mut timing)?;
        }
        timing.network_s += sampling.elapsed().as_secs_f64() - timing.guidance_s;

        let finishing = Instant::now();
        let frames = batch.finish(&values, settings)?;
        timing.other_s += finishing.elapsed().as_secs_f64();
        Ok((frames, timing, values))
    }

    /// The first stage: the frames' posed bodies (and their surfaces where a later stage or
    /// the inputs need them), bases and network inputs, as a [`Batch`] and the network's
    /// conditioned field.
    fn prepare_batch<'b>(
        &'b self,
        garment: &'b PreparedGarment,
        seq: &BodySequence,
        chunk: &'b [usize],
        surfaces: &'b mut Vec<MeshSurface>,
        settings: &Settings,
        previous: Option<&[f32]>,
    ) -> Result<(Batch<'b>, Conditioned<'b>)> {
        let data = &self.trained.data;
        let (r, dim) = (data.resolution, data.condition_dim);
        let posed = posed_bodies(self.body, seq, chunk)?;
        let tests_after = settings.inside_test || settings.resolve_penetration;
        let guided = (0..settings.steps).any(|k| settings.guidance.guides(k, settings.steps))
            || (settings.guidance.weight > 0.0 && settings.guidance.refine > 0);
        let surfaced = if tests_after || guided || self.trained.config.model.body_nearest {
            posed.len()
        } else {
            0
        };
        self.refit(&posed[..surfaced], chunk, surfaces)?;
        let surfaces = &surfaces[..surfaced];
        let mut targets = garment.targets.clone();
        let (bases, inputs) =
            self.inputs_of(garment, &mut targets, seq, chunk, surfaces, previous)?;
        let device = &self.trained.device;
        let b = chunk.len();
        let tensor = |values: &[f32]| Tensor::<1>::from_floats(values, device);
        let mask: Vec<f32> = (0..b).flat_map(|_| garment.mask.iter().copied()).collect();
        let field = Conditioned {
            model: &self.trained.model,
            members: &self.trained.members,
            position: tensor(&inputs.texels).reshape([
                b,
                self.trained.config.model.texel_channels(),
                r,
                r,
            ]),
            mask: tensor(&mask).reshape([b, 1, r, r]),
            conditions: tensor(&inputs.conditions).reshape([b, dim]),
            zero_outside: self.trained.config.training.zero_outside,
        };
        let batch = Batch {
            garment,
            chunk,
            bases,
            posed,
            surfaces,
            known: vec![ClearanceCache::default(); b],
            targets: &data.normalization.targets,
            resolution: r,
            band: settings.guidance.band_m,
        };
        Ok((batch, field))
    }
}

impl Batch<'_> {
    /// Values in the batch's normalized maps, `B * 3 * R * R`.
    fn values_len(&self) -> usize {
        self.chunk.len() * 3 * self.resolution.pow(2)
    }

    /// Draw `d`'s initial noise (draw 0 keeps the stream single-draw runs always used).
    fn noise(&self, d: usize, settings: &Settings) -> Vec<f32> {
        let plane = self.resolution.pow(2);
        let stream = if d == 0 {
            NOISE_STREAM
        } else {
            EXTRA_DRAW_STREAMS + d as u64
        };
        let mut noise = Vec::with_capacity(self.values_len());
        for &k in self.chunk {
            let step = match settings.noise {
                Noise::Shared => 0,
                Noise::PerFrame => k as u64 + 1,
            };
            let mut rng = generator(settings.seed, stream, step);
            noise.extend((0..3 * plane).map(|_| normal(&mut rng)));
        }
        noise
    }

    /// The guidance term of normalized maps `values` at `scale`: the penalty's gradient of
    /// each frame, spread to its texels and divided by the targets' std.
    fn correction(&mut self, values: &[f32], scale: f64) -> Result<Vec<f32>> {
        let plane = self.resolution.pow(2);
        let image = &self.garment.image;
        let mut correction = vec![0.0f32; values.len()];
        for ((z, out), ((base, surface), cache)) in values
            .chunks(3 * plane)
            .zip(correction.chunks_mut(3 * plane))
            .zip(self.bases.iter().zip(self.surfaces).zip(&mut self.known))
        {
            let map = self.targets.denormalize::<3>(z);
            let world = base.decode(&image.read(&map)?);
            let gradient: Vec<[f64; 3]> =
                penalty_gradient(cache.clearances(surface, &world, self.band), self.band)
                    .into_iter()
                    .map(|g| base.gradient_to_target(g))
                    .collect();
            let spread_image = image.read_transpose(&gradient)?;
            for (c, out) in out.chunks_mut(plane).enumerate() {
                let factor = scale / self.targets.std[c];
                for ((o, g), w) in out.iter_mut().zip(&spread_image).zip(&self.garment.spread) {
                    *o = (factor * g[c] * w) as f32;
                }
            }
        }
        Ok(correction)
    }

    /// One draw of the flow from its own noise, guided on the steps `settings` guide.
    fn draw(
        &mut self,
        field: &Conditioned,
        d: usize,
        settings: &Settings,
        timing: &mut Timing,
    ) -> Result<Vec<f32>> {
        let r = self.resolution;
        let b = self.chunk.len();
        let device = field.position.device();
        let tensor = |values: &[f32]| Tensor::<1>::from_floats(values, &device);
        let grid = time_grid(settings.steps, settings.shift);
        let noise = tensor(&self.noise(d, settings)).reshape([b, 3, r, r]);
        // The sampler's callback answers "no guidance" on an error; the first one is kept
        // here and ends the prediction after the draw.
        let mut failure = None;
        let x = euler(field, noise, &grid, &mut |k, s, x0_hat| {
            if failure.is_some() || !settings.guidance.guides(k, settings.steps) {
                return None;
            }
            let t = Instant::now();
            let ds = s - grid[k + 1];
            let scale = settings.guidance.weight.min(1.0 / ds);
            let correction = x0_hat
                .clone()
                .try_into_vec_as::<f32>()
                .map_err(|e| Error::TensorData {
                    what: "the sampler's estimate",
                    problem: format!("{e:?}"),
                })
                .and_then(|values| self.correction(&values, scale));
            timing.guidance_s += t.elapsed().as_secs_f64();
            match correction {
                Ok(c) => Some(tensor(&c).reshape([b, 3, r, r])),
                Err(e) => {
                    failure = Some(e);
                    None
                }
            }
        });
        if let Some(e) = failure {
            return Err(e);
        }
        x.try_into_vec_as().map_err(|e| Error::TensorData {
            what: "the sampler's output",
            problem: format!("{e:?}"),
        })
    }

    /// Refinement passes on the sample itself: each moves every vertex in the band by its
    /// depth below the band's edge, as far as the texels carry it.
    fn refine(&mut self, values: &mut [f32], passes: usize, timing: &mut Timing) -> Result<()> {
        for _ in 0..passes {
            let t = Instant::now();
            let correction = self.correction(values, 1.0)?;
            values.iter_mut().zip(correction).for_each(|(v, c)| *v -= c);
            timing.guidance_s += t.elapsed().as_secs_f64();
        }
        Ok(())
    }

    /// The last stage: the maps decoded to world vertices, tested against the bodies (and
    /// pushed out) where `settings` ask.
    fn finish(&mut self, values: &[f32], settings: &Settings) -> Result<Vec<PredictedFrame>> {
        let plane = self.resolution.pow(2);
        let tests_after = settings.inside_test || settings.resolve_penetration;
        let posed = std::mem::take(&mut self.posed);
        values
            .chunks(3 * plane)
            .zip(&self.bases)
            .zip(self.chunk.iter().zip(posed))
            .zip(self.known.iter_mut())
            .enumerate()
            .map(|(i, (((z, base), (&index, body)), cache))| {
                let map = self.targets.denormalize::<3>(z);
                let mut world = base.decode(&self.garment.image.read(&map)?);
                let (mut inside, mut max_penetration_m, mut pushed) = (None, None, 0);
                if tests_after {
                    let c = cache.clearances(&self.surfaces[i], &world, self.band);
                    let (n, deepest) = penetration(c);
                    (inside, max_penetration_m) = (Some(n), Some(deepest));
                    if settings.resolve_penetration {
                        pushed = push_out(&mut world, c, self.band);
                    }
                }
                Ok(PredictedFrame {
                    index,
                    garment: world,
                    body,
                    inside,
                    max_penetration_m,
                    pushed,
                })
            })
            .collect()
    }
}
