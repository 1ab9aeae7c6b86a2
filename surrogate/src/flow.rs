//! The maths of rectified flow, in one place for training and sampling: the interpolation
//! z_s = (1 - s) z0 + s eps between data (s = 0) and noise (s = 1), what the network is
//! trained towards (the velocity eps - z0 or the data z0), the velocity an output stands for
//! and the data estimate a velocity implies, the time grid, and the Euler integrator from
//! noise to data with Sana's optional time shift and a hook that corrects the velocity at each
//! step (intersection guidance plugs in there). Frames are independent: a batch is any set of
//! frames, and frames that share their initial noise stay coherent over time.

use burn::prelude::*;

use crate::model::{Dit, Prediction};

/// The state at time `s` between the data value `z0` and the noise `eps`.
pub fn interpolate(z0: f32, eps: f32, s: f32) -> f32 {
    (1.0 - s) * z0 + s * eps
}

/// What a network that outputs `prediction` is trained towards at a value `z0` noised by
/// `eps`: the velocity eps - z0 (constant along the straight path) or z0 itself.
pub fn target(prediction: Prediction, z0: f32, eps: f32) -> f32 {
    match prediction {
        Prediction::Velocity => eps - z0,
        Prediction::Data => z0,
    }
}

/// The data estimate x0 = x - s v of state `x` at time `s` moving with velocity `v`.
pub fn data_estimate(x: Tensor<4>, v: Tensor<4>, s: f64) -> Tensor<4> {
    x - v.mul_scalar(s as f32)
}

/// The times of an `steps`-step schedule from 1 to 0: s_k = 1 - k / steps, shifted by
/// s' = k s / (1 + (k - 1) s) when `shift` is not 1 (shift > 1 spends more steps at high
/// noise).
pub fn time_grid(steps: usize, shift: f64) -> Vec<f64> {
    (0..=steps)
        .map(|k| {
            let s = 1.0 - k as f64 / steps.max(1) as f64;
            shift * s / (1.0 + (shift - 1.0) * s)
        })
        .collect()
}

/// What the sampler asks a velocity of: the model with a frame batch's fixed inputs.
pub trait Velocity {
    /// The velocity `[B, 3, R, R]` at state `x` `[B, 3, R, R]` and time `s`.
    fn velocity(&self, x: Tensor<4>, s: f64) -> Tensor<4>;
}

/// A model with the fixed inputs of a batch of frames: position maps `[B, 3, R, R]`, masks
/// `[B, 1, R, R]`, conditions `[B, D]` (all normalized as in training).
pub struct Conditioned<'a> {
    /// The model.
    pub model: &'a Dit,
    /// Further networks of one configuration whose outputs are averaged with `model`'s (an
    /// ensemble's other members; empty for one model).
    pub members: &'a [Dit],
    /// Position maps.
    pub position: Tensor<4>,
    /// Loss masks.
    pub mask: Tensor<4>,
    /// Condition vectors.
    pub conditions: Tensor<2>,
    /// Whether an `x0` model's estimate is set to zero outside the mask (models trained with
    /// `zero_outside`: their state there stays the noise they were trained with).
    pub zero_outside: bool,
}

impl Velocity for Conditioned<'_> {
    fn velocity(&self, x: Tensor<4>, s: f64) -> Tensor<4> {
        let b = x.dims()[0];
        let time = Tensor::<1>::full([b], s as f32, &x.device());
        let forward = |model: &Dit| {
            model.forward(
                x.clone(),
                self.position.clone(),
                self.mask.clone(),
                time.clone(),
                self.conditions.clone(),
            )
        };
        let mut out = forward(self.model);
        for member in self.members {
            out = out + forward(member);
        }
        let out = match self.members.len() {
            0 => out,
            n => out.div_scalar((n + 1) as f32),
        };
        let out = if self.zero_outside && self.model.config.prediction == Prediction::Data {
            out * self.mask.clone().repeat_dim(1, 3)
        } else {
            out
        };
        as_velocity(self.model.config.prediction, x, out, s)
    }
}

/// The velocity a network output `out` stands for at state `x` and time `s`: itself, or for
/// an `x0` model the velocity that carries x to the estimate in the time left (the sampler
/// never asks at s = 0).
pub fn as_velocity(prediction: Prediction, x: Tensor<4>, out: Tensor<4>, s: f64) -> Tensor<4> {
    match prediction {
        Prediction::Velocity => out,
        Prediction::Data => (x - out).div_scalar(s.max(1e-6) as f32),
    }
}

/// Integrates from `noise` (the state at s = 1) over `grid` (from [`time_grid`]) and returns
/// the state at s = 0, the sampled normalized target maps. `correct(k, s, x0_hat)` may return
/// a term added to the velocity of step `k` (x0_hat = x - s v, the current estimate of the
/// data).
pub fn euler(
    field: &dyn Velocity,
    noise: Tensor<4>,
    grid: &[f64],
    correct: &mut dyn FnMut(usize, f64, &Tensor<4>) -> Option<Tensor<4>>,
) -> Tensor<4> {
    let mut x = noise;
    for (k, pair) in grid.windows(2).enumerate() {
        let (s, next) = (pair[0], pair[1]);
        let mut v = field.velocity(x.clone(), s);
        let x0_hat = data_estimate(x.clone(), v.clone(), s);
        if let Some(extra) = correct(k, s, &x0_hat) {
            v = v + extra;
        }
        x = x + v.mul_scalar((next - s) as f32);
    }
    x
}

#[cfg(test)]
mod tests {
    use super::*;
    use burn::tensor::Distribution;

    /// The exact velocity of rectified flow towards one data point z0: (x - z0) / s.
    struct Towards(Tensor<4>);

    impl Velocity for Towards {
        fn velocity(&self, x: Tensor<4>, s: f64) -> Tensor<4> {
            (x - self.0.clone()).div_scalar(s as f32)
        }
    }

    /// A perfect `x0` model of one data point: it always answers z0.
    struct PredictsData(Tensor<4>);

    impl Velocity for PredictsData {
        fn velocity(&self, x: Tensor<4>, s: f64) -> Tensor<4> {
            as_velocity(Prediction::Data, x, self.0.clone(), s)
        }
    }

    #[test]
    fn an_x0_output_is_integrated_to_itself() {
        let device = Device::flex();
        let _random = crate::seeded(&device, 4);
        let n = Distribution::Normal(0.0, 1.0);
        let z0 = Tensor::<4>::random([2, 3, 8, 8], n, &device);
        let noise = Tensor::<4>::random([2, 3, 8, 8], n, &device);
        for steps in [1, 2, 7] {
            let out = euler(
                &PredictsData(z0.clone()),
                noise.clone(),
                &time_grid(steps, 2.0),
                &mut |_, _, x0| {
                    assert!(worst(x0.clone(), z0.clone()) < 1e-4);
                    None
                },
            );
            assert!(worst(out, z0.clone()) < 1e-4, "{steps} steps");
        }
        // The velocity output is passed through unchanged.
        let v = as_velocity(Prediction::Velocity, noise.clone(), z0.clone(), 0.5);
        assert_eq!(worst(v, z0), 0.0);
    }

    fn worst(a: Tensor<4>, b: Tensor<4>) -> f32 {
        (a - b).abs().max().into_scalar::<f32>()
    }

    #[test]
    fn an_ensemble_field_is_the_mean_of_its_members_fields() {
        let device = Device::flex();
        let _random = crate::seeded(&device, 5);
        let config = crate::model::tests::tiny();
        let (a, b) = (Dit::new(&config, &device), Dit::new(&config, &device));
        let n = Distribution::Normal(0.0, 1.0);
        let position = Tensor::<4>::random([2, config.texel_channels(), 32, 32], n, &device);
        let conditions = Tensor::<2>::random([2, 5], n, &device);
        let x = Tensor::<4>::random([2, 3, 32, 32], n, &device);
        let field = |model: &Dit, members: &[Dit]| {
            Conditioned {
                model,
                members,
                position: position.clone(),
                mask: Tensor::ones([2, 1, 32, 32], &device),
                conditions: conditions.clone(),
                zero_outside: true,
            }
            .velocity(x.clone(), 0.7)
        };
        let (alone_a, alone_b) = (field(&a, &[]), field(&b, &[]));
        assert!(
            worst(alone_a.clone(), alone_b.clone()) > 1e-3,
            "two distinct members"
        );
        let pair = field(&a, std::slice::from_ref(&b));
        assert!(worst(pair, (alone_a + alone_b).div_scalar(2.0)) < 1e-5);
    }

    #[test]
    fn the_grid_runs_from_one_to_zero_and_shifts_towards_noise() {
        let g = time_grid(4, 1.0);
        assert_eq!(g, vec![1.0, 0.75, 0.5, 0.25, 0.0]);
        let shifted = time_grid(4, 3.0);
        assert_eq!((shifted[0], shifted[4]), (1.0, 0.0));
        assert!(shifted[2] > 0.5, "{shifted:?}");
    }

    #[test]
    fn euler_on_the_exact_field_lands_on_the_data_in_any_number_of_steps() {
        let device = Device::flex();
        let _random = crate::seeded(&device, 9);
        let n = Distribution::Normal(0.0, 1.0);
        let z0 = Tensor::<4>::random([2, 3, 8, 8], n, &device);
        let noise = Tensor::<4>::random([2, 3, 8, 8], n, &device);
        for steps in [1, 2, 7] {
            let mut calls = 0;
            let out = euler(
                &Towards(z0.clone()),
                noise.clone(),
                &time_grid(steps, 1.0),
                &mut |_, _, x0| {
                    calls += 1;
                    // The estimate of the data is exact at every step for this field.
                    assert!(worst(x0.clone(), z0.clone()) < 1e-4);
                    None
                },
            );
            assert_eq!(calls, steps);
            assert!(worst(out, z0.clone()) < 1e-4, "{steps} steps");
        }
    }

    #[test]
    fn a_correction_moves_the_result() {
        let device = Device::flex();
        let z0 = Tensor::<4>::zeros([1, 3, 8, 8], &device);
        let noise = Tensor::<4>::ones([1, 3, 8, 8], &device);
        // On the exact field towards 0 from 1 in 4 steps, a correction of +2 on steps 2 and 3
        // gives x = 1, 0.75, 0.5, then 0.5 - 0.25 (1 + 2) = -0.25, then -0.25 - 0.25 (-1 + 2)
        // = -0.5 (by hand).
        let out = euler(&Towards(z0), noise, &time_grid(4, 1.0), &mut |k, _, x0| {
            (k >= 2).then(|| x0.ones_like().mul_scalar(2.0))
        });
        let v: Vec<f32> = out.try_into_vec_as().unwrap();
        assert!(v.iter().all(|&x| (x + 0.5).abs() < 1e-5), "{:?}", &v[..3]);
    }
}
