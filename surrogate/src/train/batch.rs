//! Rectified-flow batches: frames drawn from a split, times and noise drawn from a generator
//! seeded by (run seed, step), so any step's batch is the same whether the run was resumed or
//! not; and the weighted velocity loss.
//!
//! Noise is drawn by [`crate::noise`], shared with sampling.

use burn::prelude::*;
use rand::Rng;
use rand_chacha::ChaCha8Rng;

use crate::data::{Frames, TrainingTensors, previous_state_map};
use crate::flow;
use crate::model::{DitConfig, Prediction};
use crate::noise::{generator, normal, smooth_field};
use crate::run::{Objective, TimeSampling, TrainConfig};

/// Stream of the training batches.
pub const TRAIN_STREAM: u64 = 1;
/// Stream of the validation draws.
pub const VALIDATION_STREAM: u64 = 2;

/// Cells per side of the previous state's noise field: errors that span an eighth of the
/// geometry image or more.
const PREVIOUS_NOISE_CELLS: usize = 8;

/// A time in (0, 1], always 1 for the regression objective.
pub fn time(rng: &mut ChaCha8Rng, training: &TrainConfig) -> f32 {
    if training.objective == Objective::Regression {
        return 1.0;
    }
    match training.time_sampling {
        TimeSampling::Uniform => rng.random::<f32>(),
        TimeSampling::LogitNormal => {
            let z = training.logit_mean + training.logit_std * f64::from(normal(rng));
            (1.0 / (1.0 + (-z).exp())) as f32
        }
    }
}

/// How a batch is made from frames: what the model takes and what it is trained towards.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Recipe {
    /// Loss weight of inside texels relative to read-back-only ones.
    pub inside_weight: f32,
    /// What the network outputs.
    pub prediction: Prediction,
    /// Targets zeroed outside the loss mask before noising.
    pub zero_outside: bool,
    /// Body channels the texel inputs include (the first ones of the tensors' body inputs).
    pub body_channels: usize,
    /// With a previous-state model, the spread of the smooth noise laid on the previous
    /// frame's target map (normalized units): at prediction that map is the model's own,
    /// with its errors.
    pub previous_noise: Option<f32>,
    /// The spread of the Gaussian noise laid on each normalized condition value (0: none).
    pub condition_noise: f32,
}

impl Recipe {
    /// The recipe of a model trained by `training`.
    pub fn new(model: &DitConfig, training: &TrainConfig) -> Self {
        Self {
            inside_weight: training.inside_weight as f32,
            prediction: model.prediction,
            zero_outside: training.zero_outside,
            body_channels: model.body_channels(),
            previous_noise: model
                .previous_state
                .then_some(training.previous_noise as f32),
            condition_noise: training.condition_noise as f32,
        }
    }
}

/// One batch as plain arrays (channels first, flat).
#[derive(Debug, Clone, Default)]
pub struct Batch {
    /// Frames.
    pub size: usize,
    /// z_s = (1 - s) z0 + s eps, `[B, 3, R, R]`.
    pub noisy: Vec<f32>,
    /// The texel inputs: position map, then the body inputs and the previous state when the
    /// model takes them, `[B, P, R, R]`.
    pub position: Vec<f32>,
    /// The loss masks, `[B, 1, R, R]`.
    pub mask: Vec<f32>,
    /// Loss weight per texel, `[B, 1, R, R]`.
    pub weight: Vec<f32>,
    /// `[B]`.
    pub time: Vec<f32>,
    /// `[B, D]`.
    pub conditions: Vec<f32>,
    /// What the network should output: eps - z0 (velocity) or z0 (x0), `[B, 3, R, R]`.
    pub target: Vec<f32>,
}

impl Batch {
    /// The batch of `frames` (indices into `split`) at times `times` with noise from `rng`.
    pub fn new(
        tensors: &TrainingTensors,
        split: &Frames,
        frames: &[usize],
        times: &[f32],
        recipe: Recipe,
        rng: &mut ChaCha8Rng,
    ) -> Self {
        Self::with_own_previous(tensors, split, frames, times, recipe, rng, &[])
    }

    /// [`Self::new`] where a previous-state model is given its own output for the frame
    /// before: `own[i]`, the normalized map `[3, R, R]` it made, replaces frame `i`'s simulated
    /// previous frame and its noise (frames past `own`'s end, or `None`, keep those).
    pub fn with_own_previous(
        tensors: &TrainingTensors,
        split: &Frames,
        frames: &[usize],
        times: &[f32],
        recipe: Recipe,
        rng: &mut ChaCha8Rng,
        own: &[Option<Vec<f32>>],
    ) -> Self {
        let Recipe {
            inside_weight,
            prediction,
            zero_outside,
            body_channels,
            previous_noise,
            condition_noise,
        } = recipe;
        let stored = tensors.manifest.body_channels();
        let r = tensors.resolution();
        let plane = r * r;
        let d = tensors.manifest.condition_dim;
        let mut b = Self {
            size: frames.len(),
            time: times.to_vec(),
            ..Self::default()
        };
        for (i, (&f, &s)) in frames.iter().zip(times).enumerate() {
            let g = split.template[f];
            let z0 = &split.targets[f * 3 * plane..(f + 1) * 3 * plane];
            let mask = &tensors.masks[g * plane..(g + 1) * plane];
            for (k, &x) in z0.iter().enumerate() {
                let x = if zero_outside && mask[k % plane] == 0.0 {
                    0.0
                } else {
                    x
                };
                let eps = normal(rng);
                b.noisy.push(flow::interpolate(x, eps, s));
                b.target.push(flow::target(prediction, x, eps));
            }
            b.position
                .extend_from_slice(&tensors.position_maps[g * 3 * plane..(g + 1) * 3 * plane]);
            if body_channels > 0 {
                let at = f * stored * plane;
                b.position
                    .extend_from_slice(&split.bodies[at..at + body_channels * plane]);
            }
            let own_map = own.get(i).and_then(Option::as_deref);
            if let (Some(_), Some(map)) = (previous_noise, own_map) {
                let stats = &tensors.manifest.normalization.targets;
                b.position
                    .extend(previous_state_map(Some(map), mask, stats));
            } else if let Some(spread) = previous_noise {
                let previous = split
                    .previous(f)
                    .map(|p| &split.targets[p * 3 * plane..(p + 1) * 3 * plane]);
                let mut map =
                    previous_state_map(previous, mask, &tensors.manifest.normalization.targets);
                if previous.is_some() && spread > 0.0 {
                    let noise = smooth_field(rng, 3, r, PREVIOUS_NOISE_CELLS);
                    for (k, (v, n)) in map.iter_mut().zip(noise).enumerate() {
                        *v += spread * n * mask[k % plane];
                    }
                }
                b.position.extend(map);
            }
            let inside = &tensors.inside[g * plane..(g + 1) * plane];
            b.mask.extend_from_slice(mask);
            b.weight.extend(
                mask.iter()
                    .zip(inside)
                    .map(|(&m, &i)| m * (1.0 + (inside_weight - 1.0) * i)),
            );
            let conditions = &split.conditions[f * d..(f + 1) * d];
            if condition_noise > 0.0 {
                b.conditions
                    .extend(conditions.iter().map(|c| c + condition_noise * normal(rng)));
            } else {
                b.conditions.extend_from_slice(conditions);
            }
        }
        b
    }

    /// The training batch of `step`: frames uniform with replacement, times per `training`.
    pub fn training(
        tensors: &TrainingTensors,
        split: &Frames,
        training: &TrainConfig,
        recipe: Recipe,
        step: usize,
    ) -> Self {
        Self::training_with(tensors, split, training, recipe, step, |_| Vec::new())
    }

    /// [`Self::training`] with the previous states `own` gives for the drawn frames (a
    /// rollout's, [`Self::with_own_previous`]).
    pub fn training_with(
        tensors: &TrainingTensors,
        split: &Frames,
        training: &TrainConfig,
        recipe: Recipe,
        step: usize,
        own: impl FnOnce(&[usize]) -> Vec<Option<Vec<f32>>>,
    ) -> Self {
        let mut rng = generator(training.seed, TRAIN_STREAM, step as u64);
        let frames: Vec<usize> = (0..training.batch)
            .map(|_| rng.random_range(0..split.len()))
            .collect();
        let times: Vec<f32> = (0..training.batch)
            .map(|_| time(&mut rng, training))
            .collect();
        let own = own(&frames);
        Self::with_own_previous(tensors, split, &frames, &times, recipe, &mut rng, &own)
    }

    /// The model's inputs on `device`: noisy, position, mask, time, conditions.
    pub fn inputs(
        &self,
        device: &Device,
    ) -> (Tensor<4>, Tensor<4>, Tensor<4>, Tensor<1>, Tensor<2>) {
        let (b, plane) = (self.size, self.mask.len() / self.size.max(1));
        let r = (plane as f64).sqrt().round() as usize;
        let d = self.conditions.len() / b.max(1);
        let t4 = |v: &[f32], c: usize| {
            Tensor::<4>::from_data(TensorData::new(v.to_vec(), [b, c, r, r]), device)
        };
        (
            t4(&self.noisy, 3),
            t4(&self.position, self.position.len() / (b * plane).max(1)),
            t4(&self.mask, 1),
            Tensor::<1>::from_data(TensorData::new(self.time.clone(), [b]), device),
            Tensor::<2>::from_data(TensorData::new(self.conditions.clone(), [b, d]), device),
        )
    }

    /// The weighted mean squared error of the network's output `[B, 3, R, R]` against
    /// `target`: sum w (out - target)^2 / (3 sum w), a scalar `[1]`.
    pub fn loss(&self, predicted: Tensor<4>) -> Tensor<1> {
        let device = predicted.device();
        let [b, _, r, _] = predicted.dims();
        let target =
            Tensor::<4>::from_data(TensorData::new(self.target.clone(), [b, 3, r, r]), &device);
        let weight =
            Tensor::<4>::from_data(TensorData::new(self.weight.clone(), [b, 1, r, r]), &device);
        let total: f32 = self.weight.iter().sum::<f32>().max(1e-12) * 3.0;
        ((predicted - target).square() * weight)
            .sum()
            .div_scalar(total)
    }
}

/// The fixed validation set: `count` frames evenly spaced over `split`, each at its own
/// stratified time ((k + 0.5) / count; 1 for the regression objective) with noise from the
/// validation stream.
pub fn validation_batches(
    tensors: &TrainingTensors,
    split: &Frames,
    training: &TrainConfig,
    recipe: Recipe,
) -> Vec<Batch> {
    let count = training.val_frames.min(split.len());
    if count == 0 {
        return Vec::new();
    }
    let frames: Vec<usize> = (0..count).map(|k| k * split.len() / count).collect();
    let times: Vec<f32> = (0..count)
        .map(|k| match training.objective {
            Objective::Regression => 1.0,
            Objective::Flow => (k as f32 + 0.5) / count as f32,
        })
        .collect();
    let mut rng = generator(training.seed, VALIDATION_STREAM, 0);
    // Validation measures the network on the conditions as they are.
    let recipe = Recipe {
        condition_noise: 0.0,
        ..recipe
    };
    frames
        .chunks(training.batch)
        .zip(times.chunks(training.batch))
        .map(|(f, t)| Batch::new(tensors, split, f, t, recipe, &mut rng))
        .collect()
}
