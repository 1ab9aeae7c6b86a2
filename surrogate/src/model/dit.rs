//! The diffusion transformer: patchify the 7-channel input image, condition on the timestep
//! (adaLN-single) and on the condition vector (cross-attention to tokens made by a 2-layer
//! MLP), a stack of Sana blocks, unpatchify to the 3-channel velocity. No positional
//! embedding: the position map in the input is the only positional signal, so one model serves
//! templates it never saw.

use burn::module::{Initializer, Param};
use burn::nn::{Linear, LinearConfig};
use burn::prelude::*;
use burn::tensor::activation::silu;

use super::config::{DitConfig, OUTPUT_CHANNELS};
use super::layers::{CrossAttention, LinearAttention, MixFfn, dropout, norm, timestep_features};

/// Timestep MLP: 256 sinusoidal features -> Linear -> SiLU -> Linear.
#[derive(Module, Debug)]
pub struct TimestepEmbedder {
    /// `256 -> C`.
    pub fc1: Linear,
    /// `C -> C`.
    pub fc2: Linear,
}

/// Condition MLP: the condition vector -> Linear -> SiLU -> Linear -> T tokens of width C.
#[derive(Module, Debug)]
pub struct ConditionEmbedder {
    /// `D -> C`.
    pub fc1: Linear,
    /// `C -> T C`.
    pub fc2: Linear,
    /// Tokens made.
    pub tokens: usize,
}

/// One Sana block with its adaLN-single table.
#[derive(Module, Debug)]
pub struct Block {
    /// `[6, C]`, added to the shared timestep modulation: shift, scale, gate of attention,
    /// then of the Mix-FFN.
    pub table: Param<Tensor<2>>,
    /// Self-attention.
    pub attn: LinearAttention,
    /// Cross-attention to the condition tokens.
    pub cross: CrossAttention,
    /// Mix-FFN.
    pub ffn: MixFfn,
}

impl Block {
    /// Tokens `[B, N, C]`, timestep modulation `[B, 6, C]`, condition tokens `[B, T, C]` ->
    /// `[B, N, C]`; `drop`: the dropout rate of the three branches (training only).
    pub fn forward(
        &self,
        x: Tensor<3>,
        t6: Tensor<3>,
        condition: Tensor<3>,
        drop: f64,
    ) -> Tensor<3> {
        let m = t6 + self.table.val().unsqueeze::<3>();
        let part = |k: usize| m.clone().slice(s![.., k..k + 1, ..]); // [B, 1, C]
        let modulate = |x: Tensor<3>, shift: Tensor<3>, scale: Tensor<3>| {
            norm(x) * (scale.add_scalar(1.0)) + shift
        };
        let attn = self.attn.forward(modulate(x.clone(), part(0), part(1)));
        let x = x + part(2) * dropout(attn, drop);
        let x = x.clone() + dropout(self.cross.forward(x, condition), drop);
        let ffn = self.ffn.forward(modulate(x.clone(), part(3), part(4)));
        x + part(5) * dropout(ffn, drop)
    }
}

/// The model (shapes: B batch, R resolution, p patch, G = R / p, N = G^2 tokens, C width).
#[derive(Module, Debug)]
pub struct Dit {
    /// `7 p^2 -> C` per patch (channel-major within a patch, as a PyTorch `Conv2d` with
    /// kernel = stride = p flattens its weight).
    pub patch_embed: Linear,
    /// Timestep features -> `[B, C]`.
    pub t_embed: TimestepEmbedder,
    /// adaLN-single: SiLU(t) -> `[B, 6C]`, shared by all blocks.
    pub t_block: Linear,
    /// Condition vector -> condition tokens.
    pub cond_embed: ConditionEmbedder,
    /// The blocks.
    pub blocks: Vec<Block>,
    /// `[2, C]`: shift and scale of the final norm, added to t.
    pub final_table: Param<Tensor<2>>,
    /// `C -> 3 p^2`.
    pub final_linear: Linear,
    /// The configuration it was built from.
    #[module(skip)]
    pub config: DitConfig,
}

impl Dit {
    /// A new model with freshly initialized weights on `device` (seed the device first for
    /// reproducible weights). Every parameter is initialized here, not at first use, so the
    /// weights do not depend on what is drawn before the first forward.
    pub fn new(config: &DitConfig, device: &Device) -> Self {
        let (c, p) = (config.width, config.patch);
        let table = |rows: usize| {
            Initializer::Normal {
                mean: 0.0,
                std: 1.0 / (c as f64).sqrt(),
            }
            .init([rows, c], device)
        };
        let blocks = (0..config.depth)
            .map(|_| Block {
                table: table(6),
                attn: LinearAttention::new(c, config.heads, device),
                cross: CrossAttention::new(c, config.heads, device),
                ffn: MixFfn::new(c, config.hidden(), config.depthwise, device),
            })
            .collect();
        let model = Self {
            patch_embed: LinearConfig::new(config.input_channels() * p * p, c).init(device),
            t_embed: TimestepEmbedder {
                fc1: LinearConfig::new(super::config::FREQUENCY_DIM, c).init(device),
                fc2: LinearConfig::new(c, c).init(device),
            },
            t_block: LinearConfig::new(c, 6 * c).init(device),
            cond_embed: ConditionEmbedder {
                fc1: LinearConfig::new(config.condition_dim, c).init(device),
                fc2: LinearConfig::new(c, config.condition_tokens * c).init(device),
                tokens: config.condition_tokens,
            },
            blocks,
            final_table: table(2),
            final_linear: LinearConfig::new(c, OUTPUT_CHANNELS * p * p).init(device),
            config: config.clone(),
        };
        model.visit(&mut Materialize);
        model
    }

    /// Starts the layers that write into the residual stream's output, the final linear and
    /// every cross-attention's projection, at zero (PixArt's and Sana's choice): the first
    /// steps learn from the conditions instead of undoing a random output.
    pub fn zero_output_layers(mut self) -> Self {
        let device = self.final_linear.weight.device();
        let zero = |linear: &mut Linear| {
            let [i, o] = linear.weight.dims();
            linear.weight = Initializer::Zeros.init([i, o], &device);
            linear.bias = Some(Initializer::Zeros.init([o], &device));
        };
        zero(&mut self.final_linear);
        for block in &mut self.blocks {
            zero(&mut block.cross.proj);
        }
        self
    }

    /// Noisy target `[B, 3, R, R]`, texel inputs `[B, P, R, R]` (the position map, then with
    /// `body_inputs` the skinned base and its change: P = [`DitConfig::texel_channels`]),
    /// mask `[B, 1, R, R]`, timestep `[B]` in [0, 1], conditions `[B, D]` -> the velocity or
    /// the clean map `[B, 3, R, R]`.
    pub fn forward(
        &self,
        noisy: Tensor<4>,
        position: Tensor<4>,
        mask: Tensor<4>,
        timestep: Tensor<1>,
        conditions: Tensor<2>,
    ) -> Tensor<4> {
        self.forward_dropping(noisy, position, mask, timestep, conditions, 0.0)
    }

    /// [`Dit::forward`] with each block's branches dropped at `rate` (training, under
    /// autodiff; elsewhere the same as `forward`).
    pub fn forward_dropping(
        &self,
        noisy: Tensor<4>,
        position: Tensor<4>,
        mask: Tensor<4>,
        timestep: Tensor<1>,
        conditions: Tensor<2>,
        rate: f64,
    ) -> Tensor<4> {
        let x = Tensor::cat(vec![noisy, position, mask], 1);
        let [b, channels, r, _] = x.dims();
        let (p, c) = (self.config.patch, self.config.width);
        let g = r / p;
        let tokens = x
            .reshape([b, channels, g, p, g, p])
            .permute([0, 2, 4, 1, 3, 5])
            .reshape([b, g * g, channels * p * p]);
        let mut h = self.patch_embed.forward(tokens); // [B, N, C]
        let t = self
            .t_embed
            .fc2
            .forward(silu(self.t_embed.fc1.forward(timestep_features(timestep)))); // [B, C]
        let t6 = self.t_block.forward(silu(t.clone())).reshape([b, 6, c]);
        let condition = self
            .cond_embed
            .fc2
            .forward(silu(self.cond_embed.fc1.forward(conditions)))
            .reshape([b, self.cond_embed.tokens, c]);
        for block in &self.blocks {
            h = block.forward(h, t6.clone(), condition.clone(), rate);
        }
        let m = self.final_table.val().unsqueeze::<3>() + t.unsqueeze_dim::<3>(1); // [B, 2, C]
        let shift = m.clone().slice(s![.., 0..1, ..]);
        let scale = m.slice(s![.., 1..2, ..]);
        let h = norm(h) * scale.add_scalar(1.0) + shift;
        self.final_linear
            .forward(h)
            .reshape([b, g, g, OUTPUT_CHANNELS, p, p])
            .permute([0, 3, 1, 4, 2, 5])
            .reshape([b, OUTPUT_CHANNELS, r, r])
    }

    /// Trainable parameters.
    pub fn parameters(&self) -> usize {
        self.num_params()
    }
}

/// Touches every parameter so lazily initialized ones draw their values now.
struct Materialize;

impl burn::module::ModuleVisitor for Materialize {
    fn visit_float<const D: usize>(&mut self, param: &Param<Tensor<D>>) {
        let _ = param.val();
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::model::config::Depthwise;
    use burn::tensor::Distribution;

    use crate::model::tests::tiny;

    /// The count validation bounds before allocating is the count the network gets.
    #[test]
    fn the_parameter_count_is_known_before_building() {
        let device = Device::flex();
        let patch2 = DitConfig {
            patch: 2,
            mlp_ratio: 1.7,
            condition_tokens: 3,
            body_inputs: true,
            body_nearest: true,
            ..tiny()
        };
        for config in [tiny(), patch2, DitConfig::default()] {
            let built = Dit::new(&config, &device).parameters();
            assert_eq!(config.parameter_count(), built, "{config:?}");
        }
        let huge = DitConfig {
            width: 4096,
            depth: 64,
            ..DitConfig::default()
        };
        let err = huge.validate().unwrap_err().to_string();
        assert!(err.contains("parameters; at most 100000000"), "{err}");
    }

    fn inputs(
        b: usize,
        device: &Device,
    ) -> (Tensor<4>, Tensor<4>, Tensor<4>, Tensor<1>, Tensor<2>) {
        let n = Distribution::Normal(0.0, 1.0);
        (
            Tensor::random([b, 3, 32, 32], n, device),
            Tensor::random([b, 3, 32, 32], n, device),
            Tensor::random([b, 1, 32, 32], Distribution::Bernoulli(0.5), device),
            Tensor::random([b], Distribution::Default, device),
            Tensor::random([b, 5], n, device),
        )
    }

    #[test]
    fn output_has_the_input_shape_and_depends_on_every_input() {
        let device = Device::flex();
        let _random = crate::seeded(&device, 1);
        let model = Dit::new(&tiny(), &device);
        let (x, pos, mask, s, c) = inputs(2, &device);
        let out = model.forward(x.clone(), pos.clone(), mask.clone(), s.clone(), c.clone());
        assert_eq!(out.dims(), [2, 3, 32, 32]);
        let base: Vec<f32> = out.try_into_vec_as().unwrap();
        let changed = |out: Tensor<4>| {
            let v: Vec<f32> = out.try_into_vec_as().unwrap();
            v.iter()
                .zip(&base)
                .map(|(a, b)| (a - b).abs())
                .fold(0.0, f32::max)
        };
        assert!(
            changed(model.forward(
                x.clone() * 0.5,
                pos.clone(),
                mask.clone(),
                s.clone(),
                c.clone()
            )) > 1e-4
        );
        assert!(
            changed(model.forward(
                x.clone(),
                pos.clone() * 0.5,
                mask.clone(),
                s.clone(),
                c.clone()
            )) > 1e-4
        );
        assert!(
            changed(model.forward(
                x.clone(),
                pos.clone(),
                mask.clone(),
                s.clone() * 0.5,
                c.clone()
            )) > 1e-4
        );
        assert!(changed(model.forward(x, pos, mask, s, c * 0.5)) > 1e-4);
    }

    #[test]
    fn condition_path_gradients_match_finite_differences() {
        let device = Device::flex();
        let _random = crate::seeded(&device, 4);
        let model = Dit::new(&tiny(), &device);
        let autodiff = model.clone().train();
        let (x, pos, mask, s, c) = inputs(2, &device);
        let weights = Tensor::<4>::random([2, 3, 32, 32], Distribution::Normal(0.0, 1.0), &device);
        // The loss as a function of the condition vector alone: the condition MLP and every
        // block's cross-attention.
        let f = |c: Tensor<3>| {
            let d = c.device();
            let m = if d.is_autodiff() { &autodiff } else { &model };
            let fixed = |t: &Tensor<4>| Tensor::<4>::from_data(t.to_data(), &d);
            let s = Tensor::<1>::from_data(s.to_data(), &d);
            let out = m.forward(fixed(&x), fixed(&pos), fixed(&mask), s, c.reshape([2, 5]));
            (out * fixed(&weights)).sum()
        };
        let (along, random) = crate::model::layers::tests::gradient_check(&f, c.reshape([2, 1, 5]));
        assert!(
            along < 1e-2 && random < 1e-2,
            "errors {along:.2e} along the gradient, {random:.2e} across"
        );
    }

    #[test]
    fn both_depthwise_kinds_give_one_model() {
        let device = Device::flex();
        let _random = crate::seeded(&device, 2);
        let shifted = Dit::new(&tiny(), &device);
        let mut conv = shifted.clone();
        for block in &mut conv.blocks {
            block.ffn.how = Depthwise::Conv2d;
        }
        let (x, pos, mask, s, c) = inputs(1, &device);
        let a: Vec<f32> = shifted
            .forward(x.clone(), pos.clone(), mask.clone(), s.clone(), c.clone())
            .try_into_vec_as()
            .unwrap();
        let b: Vec<f32> = conv.forward(x, pos, mask, s, c).try_into_vec_as().unwrap();
        let worst = crate::model::layers::tests::largest_difference(&a, &b);
        assert!(worst < 1e-4, "largest difference {worst}");
    }

    /// Zeroed output layers give a zero output, and the final layer still gets a gradient
    /// (so training moves it on the first step).
    #[test]
    fn zeroed_output_layers_start_at_zero_and_still_learn() {
        let device = Device::flex().autodiff();
        let _random = crate::seeded(&device, 3);
        let model = Dit::new(&tiny(), &device).zero_output_layers();
        let (x, pos, mask, s, c) = inputs(2, &device);
        let out = model.forward(x, pos, mask, s, c);
        let values: Vec<f32> = out.clone().try_into_vec_as().unwrap();
        assert!(values.iter().all(|&v| v == 0.0));
        let grads = (out.sum() + 1.0).square().backward();
        let g = model
            .final_linear
            .weight
            .val()
            .grad(&grads)
            .expect("a gradient");
        let g: Vec<f32> = g.try_into_vec_as().unwrap();
        assert!(g.iter().any(|&v| v != 0.0));
    }

    /// Dropout acts under autodiff only: training's forwards differ from one another and from
    /// the plain forward, and on the inner device (validation, sampling) it is the plain one.
    #[test]
    fn dropout_drops_while_training_only() {
        let device = Device::flex();
        let _random = crate::seeded(&device, 5);
        let model = Dit::new(&tiny(), &device);
        let (x, pos, mask, s, c) = inputs(2, &device);
        let values = |out: Tensor<4>| -> Vec<f32> { out.try_into_vec_as().unwrap() };
        let run = |m: &Dit, d: &Device, rate: f64| {
            let on = |t: &Tensor<4>| Tensor::<4>::from_data(t.to_data(), d);
            let (s, c) = (
                Tensor::<1>::from_data(s.to_data(), d),
                Tensor::<2>::from_data(c.to_data(), d),
            );
            values(m.forward_dropping(on(&x), on(&pos), on(&mask), s, c, rate))
        };
        let plain = run(&model, &device, 0.0);
        assert_eq!(run(&model, &device, 0.3), plain);
        let trained = model.clone().train();
        let autodiff = device.clone().autodiff();
        // Under autodiff the Mix-FFN takes another kernel for the same function: rounding.
        let largest = crate::model::layers::tests::largest_difference;
        assert!(largest(&run(&trained, &autodiff, 0.0), &plain) < 1e-4);
        let (a, b) = (run(&trained, &autodiff, 0.3), run(&trained, &autodiff, 0.3));
        assert!(largest(&a, &plain) > 1e-3, "dropout changed nothing");
        assert!(largest(&a, &b) > 1e-3, "two draws dropped the same values");
    }
}
