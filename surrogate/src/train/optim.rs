//! What burn's optimizer does not do the way the paper's recipe needs: gradient clipping by the
//! global norm (burn's `GradientClippingConfig::Norm` clips each tensor by its own norm) and
//! the exponential moving average of the weights.

use burn::module::{ModuleMapper, ModuleVisitor, Param};
use burn::optim::GradientsParams;
use burn::prelude::*;

use crate::model::Dit;
use crate::run::TrainConfig;

struct SquaredNorm<'a> {
    grads: &'a GradientsParams,
    sum: f64,
}

impl ModuleVisitor for SquaredNorm<'_> {
    fn visit_float<const D: usize>(&mut self, param: &Param<Tensor<D>>) {
        if let Some(g) = self.grads.get::<D>(param.id) {
            self.sum += f64::from(g.square().sum().into_scalar::<f32>());
        }
    }
}

struct Scale<'a> {
    grads: &'a mut GradientsParams,
    factor: f32,
}

impl ModuleVisitor for Scale<'_> {
    fn visit_float<const D: usize>(&mut self, param: &Param<Tensor<D>>) {
        if let Some(g) = self.grads.remove::<D>(param.id) {
            self.grads
                .register::<D>(param.id, g.mul_scalar(self.factor));
        }
    }
}

/// Scales `grads` down to global L2 norm `max_norm` when larger (`max_norm` 0: never);
/// returns the norm before clipping.
pub fn clip_global_norm(model: &Dit, grads: &mut GradientsParams, max_norm: f64) -> f64 {
    let mut norm = SquaredNorm { grads, sum: 0.0 };
    model.visit(&mut norm);
    let norm = norm.sum.sqrt();
    if max_norm > 0.0 && norm > max_norm {
        model.visit(&mut Scale {
            grads,
            factor: (max_norm / (norm + 1e-6)) as f32,
        });
    }
    norm
}

/// Every float parameter of a model, flattened, in visiting order.
struct Flatten(Vec<Tensor<1>>);

impl ModuleVisitor for Flatten {
    fn visit_float<const D: usize>(&mut self, param: &Param<Tensor<D>>) {
        let t = param.val().inner();
        let n = t.shape().num_elements();
        self.0.push(t.reshape([n]));
    }
}

/// `ema <- decay ema + (1 - decay) model`, parameter by parameter in visiting order (both
/// models have one structure).
struct Blend {
    source: std::vec::IntoIter<Tensor<1>>,
    decay: f32,
}

impl ModuleMapper for Blend {
    fn map_float<const D: usize>(&mut self, param: Param<Tensor<D>>) -> Param<Tensor<D>> {
        let source = self
            .source
            .next()
            .expect("the EMA and the model have one structure");
        let decay = self.decay;
        param.map(|e| {
            let dims = e.dims();
            e.mul_scalar(decay) + source.reshape(dims).mul_scalar(1.0 - decay)
        })
    }
}

/// The EMA decay at `step` (0-based): `min(decay, (1 + step) / (10 + step))`, so early
/// averages are not dominated by the random initialization.
pub fn ema_decay(decay: f64, step: usize) -> f64 {
    decay.min((1.0 + step as f64) / (10.0 + step as f64))
}

/// The averaging decay of `step` (0-based): the EMA's, or from `swa_start` on `k / (k + 1)`
/// at the k-th step since, which makes the running average the plain mean of those steps'
/// weights (the first of them replaces the EMA).
pub fn average_decay(training: &TrainConfig, step: usize) -> f64 {
    match training.swa_start {
        start if start > 0 && step >= start => {
            let k = (step - start) as f64;
            k / (k + 1.0)
        }
        _ => ema_decay(training.ema_decay, step),
    }
}

/// One EMA update of `ema` (plain tensors) towards `model`.
pub fn update_ema(ema: Dit, model: &Dit, decay: f64) -> Dit {
    let mut flat = Flatten(Vec::new());
    model.visit(&mut flat);
    ema.map(&mut Blend {
        source: flat.0.into_iter(),
        decay: decay as f32,
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::model::DitConfig;
    use burn::tensor::Distribution;

    #[test]
    fn a_tiny_model_overfits_eight_samples() {
        let device = Device::flex().autodiff();
        let _random = crate::seeded(&device, 7);
        // Patch 2 and width 32: white-noise velocity needs a token wide enough to carry it.
        let config = DitConfig {
            patch: 2,
            width: 32,
            ..crate::model::tests::tiny()
        };
        let mut model = Dit::new(&config, &device);
        let mut ema = model.valid();
        let training = TrainConfig {
            lr: 3e-3,
            ..TrainConfig::default()
        };
        let mut optim = crate::train::checkpoint::optimizer(&training);
        let plain = Device::flex();
        let n = Distribution::Normal(0.0, 1.0);
        // Smooth, distinct targets, as garment maps are (white noise is not what the model
        // is for).
        let smooth: Vec<f32> = (0..8 * 3 * 32 * 32)
            .map(|i| {
                let (b, c, y, x) = (i / 3072, i / 1024 % 3, i / 32 % 32, i % 32);
                let (b, c, y, x) = (b as f32, c as f32, y as f32, x as f32);
                (0.1 * (b + 1.0) * y + c).sin() * (0.07 * (c + 1.0) * x + b).cos()
            })
            .collect();
        let z0 = Tensor::<4>::from_data(TensorData::new(smooth, [8, 3, 32, 32]), &plain);
        let eps = Tensor::<4>::random([8, 3, 32, 32], n, &plain);
        let s = Tensor::<1>::from_data([0.1f32, 0.2, 0.3, 0.4, 0.5, 0.6, 0.7, 0.8], &plain);
        let s4 = s.clone().reshape([8, 1, 1, 1]);
        let noisy = z0.clone() * (s4.clone().neg().add_scalar(1.0)) + eps.clone() * s4;
        let velocity = eps - z0;
        let position = Tensor::<4>::random([8, 3, 32, 32], n, &plain);
        let mask = Tensor::<4>::ones([8, 1, 32, 32], &plain);
        let conditions = Tensor::<2>::random([8, 5], n, &plain);
        let loss_of = |m: &Dit| {
            (m.forward(
                noisy.clone(),
                position.clone(),
                mask.clone(),
                s.clone(),
                conditions.clone(),
            ) - velocity.clone())
            .square()
            .mean()
        };
        let start = f64::from(loss_of(&model).into_scalar::<f32>());
        let mut last = start;
        for step in 0..300 {
            let loss = loss_of(&model);
            last = f64::from(loss.clone().into_scalar::<f32>());
            if last < 0.1 * start {
                break;
            }
            let mut grads = GradientsParams::from_grads(loss.backward(), &model);
            let norm = clip_global_norm(&model, &mut grads, 1.0);
            assert!(norm.is_finite() && norm > 0.0);
            model = optim.step(training.lr, model, grads);
            ema = update_ema(ema, &model, ema_decay(0.99, step));
        }
        assert!(
            last < 0.1 * start,
            "loss {start:.4} -> {last:.4} in 300 steps"
        );
        // The EMA follows the weights: it fits better than at the start.
        let ema_loss = f64::from(loss_of(&ema).into_scalar::<f32>());
        assert!(
            ema_loss < 0.5 * start,
            "EMA loss {ema_loss:.4}, start {start:.4}"
        );
    }

    #[test]
    fn swa_averages_the_weights_of_every_step_since_its_start() {
        let device = Device::flex();
        let _random = crate::seeded(&device, 9);
        let config = crate::model::tests::tiny();
        let training = TrainConfig {
            steps: 10,
            swa_start: 6,
            ..TrainConfig::default()
        };
        let first = |m: &Dit| {
            m.final_linear
                .weight
                .val()
                .into_data()
                .try_to_vec::<f32>()
                .unwrap()
        };
        let mut average = Dit::new(&config, &device);
        let mut sum = vec![0.0f64; first(&average).len()];
        for step in 0..training.steps {
            let model = Dit::new(&config, &device);
            if step >= training.swa_start {
                for (s, w) in sum.iter_mut().zip(first(&model)) {
                    *s += f64::from(w);
                }
            }
            average = update_ema(average, &model, average_decay(&training, step));
        }
        let n = (training.steps - training.swa_start) as f64;
        for (a, s) in first(&average).into_iter().zip(sum) {
            assert!((f64::from(a) - s / n).abs() < 1e-5, "{a} against {}", s / n);
        }
        // Before the start it is the EMA's decay.
        assert_eq!(average_decay(&training, 5), ema_decay(0.999, 5));
    }

    #[test]
    fn clipping_scales_to_the_global_norm() {
        let device = Device::flex().autodiff();
        let _random = crate::seeded(&device, 8);
        let config = DitConfig {
            depth: 1,
            condition_dim: 3,
            ..crate::model::tests::tiny()
        };
        let model = Dit::new(&config, &device);
        let plain = Device::flex();
        let n = Distribution::Normal(0.0, 1.0);
        let out = model.forward(
            Tensor::random([2, 3, 32, 32], n, &plain),
            Tensor::random([2, 3, 32, 32], n, &plain),
            Tensor::ones([2, 1, 32, 32], &plain),
            Tensor::from_data([0.3f32, 0.7], &plain),
            Tensor::random([2, 3], n, &plain),
        );
        let mut grads = GradientsParams::from_grads(out.square().sum().backward(), &model);
        let before = clip_global_norm(&model, &mut grads, 0.5);
        assert!(before > 0.5, "norm {before}");
        let after = clip_global_norm(&model, &mut grads, 0.0);
        assert!((after - 0.5).abs() < 1e-3, "norm after clipping {after}");
    }
}
