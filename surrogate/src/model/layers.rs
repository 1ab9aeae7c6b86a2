//! The pieces of a Sana block: ReLU linear attention, cross-attention to condition tokens, the
//! Mix-FFN with its 3 x 3 depthwise convolution, an affine-free layer norm and the timestep's
//! sinusoidal features. Shapes: B batch, N tokens, C width, T condition tokens.

use burn::module::{Initializer, Param};
use burn::nn::{Linear, LinearConfig};
use burn::prelude::*;
use burn::tensor::TensorData;
use burn::tensor::activation::{relu, silu, softmax};
use burn::tensor::module::conv2d;
use burn::tensor::ops::{ConvOptions, PadMode};

use super::config::{Depthwise, FREQUENCY_DIM};

/// Added to the linear attention's denominator (Sana's fp32 value).
pub const ATTENTION_EPS: f32 = 1e-8;
/// Layer norm's variance floor (Sana's and DiT's 1e-6).
pub const NORM_EPS: f32 = 1e-6;

/// Layer norm over the last dimension with no learnable scale or shift: adaLN supplies both.
pub fn norm(x: Tensor<3>) -> Tensor<3> {
    let mean = x.clone().mean_dim(2);
    let centred = x - mean;
    let var = centred.clone().square().mean_dim(2);
    centred / (var + NORM_EPS).sqrt()
}

/// Zeroes a `rate` fraction of `x`'s values and scales the rest by `1 / (1 - rate)`, under
/// autodiff only (training): validation and sampling, which run on the inner device, get `x`.
/// Functional rather than `burn::nn::Dropout`, whose module field would enter the weights'
/// record; the masks come from the device's generator, which training seeds per step.
pub fn dropout<const D: usize>(x: Tensor<D>, rate: f64) -> Tensor<D> {
    if rate == 0.0 || !x.device().is_autodiff() {
        return x;
    }
    let keep = 1.0 - rate;
    let mask = x.random_like(burn::tensor::Distribution::Bernoulli(keep));
    x * mask / keep
}

/// Sinusoidal features of `s * 1000` for rectified-flow time `s` in [0, 1]: `[B] -> [B, 256]`
/// (cosines, then sines, DiT's order).
pub fn timestep_features(s: Tensor<1>) -> Tensor<2> {
    let half = FREQUENCY_DIM / 2;
    let device = s.device();
    let freqs: Vec<f32> = (0..half)
        .map(|i| (-(10000f64.ln()) * i as f64 / half as f64).exp() as f32)
        .collect();
    let freqs = Tensor::<1>::from_data(freqs.as_slice(), &device).unsqueeze::<2>();
    let args = s.mul_scalar(1000.0).unsqueeze_dim::<2>(1) * freqs;
    Tensor::cat(vec![args.clone().cos(), args.sin()], 1)
}

/// Splits `[B, L, parts * H * d]` into `parts` tensors `[B, H, L, d]`.
fn heads(x: Tensor<3>, parts: usize, h: usize) -> Vec<Tensor<4>> {
    let [b, l, width] = x.dims();
    let d = width / parts / h;
    let x = x.reshape([b, l, parts, h, d]);
    (0..parts)
        .map(|i| {
            x.clone()
                .slice(s![.., .., i..i + 1, .., ..])
                .reshape([b, l, h, d])
                .swap_dims(1, 2)
        })
        .collect()
}

/// `[B, H, L, d] -> [B, L, H * d]`.
fn merge_heads(x: Tensor<4>) -> Tensor<3> {
    let [b, h, l, d] = x.dims();
    x.swap_dims(1, 2).reshape([b, l, h * d])
}

/// Sana's ReLU linear attention: cost linear in the token count.
#[derive(Module, Debug)]
pub struct LinearAttention {
    /// `C -> 3C`, no bias.
    pub qkv: Linear,
    /// `C -> C`.
    pub proj: Linear,
    /// Heads.
    pub heads: usize,
}

impl LinearAttention {
    /// A new attention of `width` over `heads` heads.
    pub fn new(width: usize, heads: usize, device: &Device) -> Self {
        Self {
            qkv: LinearConfig::new(width, 3 * width)
                .with_bias(false)
                .init(device),
            proj: LinearConfig::new(width, width).init(device),
            heads,
        }
    }

    /// `[B, N, C] -> [B, N, C]`: o_n = (sum_m v_m phi(k_m)^T) phi(q_n) / (sum_m phi(k_m)^T
    /// phi(q_n) + eps), phi = ReLU, no 1/sqrt(d) scale.
    pub fn forward(&self, x: Tensor<3>) -> Tensor<3> {
        let mut qkv = heads(self.qkv.forward(x), 3, self.heads).into_iter();
        let (q, k, v) = (
            relu(qkv.next().expect("q")),
            relu(qkv.next().expect("k")),
            qkv.next().expect("v"),
        );
        let kv = k.clone().swap_dims(2, 3).matmul(v); // [B, H, d, d]
        let numerator = q.clone().matmul(kv); // [B, H, N, d]
        let denominator = q.matmul(k.sum_dim(2).swap_dims(2, 3)); // [B, H, N, 1]
        self.proj
            .forward(merge_heads(numerator / (denominator + ATTENTION_EPS)))
    }
}

/// Multi-head softmax attention from the tokens to the condition tokens.
#[derive(Module, Debug)]
pub struct CrossAttention {
    /// Queries from the tokens, `C -> C`.
    pub q: Linear,
    /// Keys and values from the condition tokens, `C -> 2C`.
    pub kv: Linear,
    /// `C -> C`.
    pub proj: Linear,
    /// Heads.
    pub heads: usize,
}

impl CrossAttention {
    /// A new cross-attention of `width` over `heads` heads.
    pub fn new(width: usize, heads: usize, device: &Device) -> Self {
        Self {
            q: LinearConfig::new(width, width).init(device),
            kv: LinearConfig::new(width, 2 * width).init(device),
            proj: LinearConfig::new(width, width).init(device),
            heads,
        }
    }

    /// Tokens `[B, N, C]`, condition tokens `[B, T, C]` -> `[B, N, C]`.
    pub fn forward(&self, x: Tensor<3>, condition: Tensor<3>) -> Tensor<3> {
        let q = heads(self.q.forward(x), 1, self.heads).remove(0); // [B, H, N, d]
        let d = q.dims()[3];
        let mut kv = heads(self.kv.forward(condition), 2, self.heads).into_iter();
        let (k, v) = (kv.next().expect("k"), kv.next().expect("v")); // [B, H, T, d]
        let logits = q.matmul(k.swap_dims(2, 3)).div_scalar((d as f32).sqrt()); // [B, H, N, T]
        self.proj.forward(merge_heads(softmax(logits, 3).matmul(v)))
    }
}

/// A 3 x 3 depthwise convolution with zero padding: weight `[K, 1, 3, 3]` (PyTorch's layout
/// for `groups = K`) and bias `[K]`.
#[derive(Module, Debug)]
pub struct DepthwiseConv {
    /// `[K, 1, 3, 3]`.
    pub weight: Param<Tensor<4>>,
    /// `[K]`.
    pub bias: Param<Tensor<1>>,
}

impl DepthwiseConv {
    /// A new convolution over `channels`, initialized like PyTorch's (uniform in +-1/3:
    /// fan-in 9).
    pub fn new(channels: usize, device: &Device) -> Self {
        let bound = 1.0 / 3.0;
        let uniform = Initializer::Uniform {
            min: -bound,
            max: bound,
        };
        Self {
            weight: uniform.init([channels, 1, 3, 3], device),
            bias: uniform.init([channels], device),
        }
    }

    /// `[B, K, G, G] -> [B, K, G, G]`, computed as `how` says (the same function).
    pub fn forward(&self, x: Tensor<4>, how: Depthwise) -> Tensor<4> {
        let [_, k, h, w] = x.dims();
        match how {
            Depthwise::Conv2d => conv2d(
                x,
                self.weight.val(),
                Some(self.bias.val()),
                ConvOptions::new([1, 1], [1, 1], [1, 1], k),
            ),
            Depthwise::Shifted => {
                let padded = x.pad((1, 1, 1, 1), PadMode::Constant(0.0));
                let weight = self.weight.val();
                let mut out = self.bias.val().reshape([1, k, 1, 1]);
                for ky in 0..3 {
                    for kx in 0..3 {
                        let tap = weight
                            .clone()
                            .slice(s![.., .., ky..ky + 1, kx..kx + 1])
                            .reshape([1, k, 1, 1]);
                        let shifted = padded.clone().slice(s![.., .., ky..ky + h, kx..kx + w]);
                        out = out + shifted * tap;
                    }
                }
                out
            }
        }
    }
}

/// Sana's Mix-FFN (GLUMBConv): 1 x 1 `C -> 2H` + SiLU, 3 x 3 depthwise over the token grid,
/// split into (x, gate), x * SiLU(gate), 1 x 1 `H -> C`.
#[derive(Module, Debug)]
pub struct MixFfn {
    /// `C -> 2H`.
    pub inverted: Linear,
    /// Over the 2H channels.
    pub depthwise: DepthwiseConv,
    /// `H -> C`.
    pub point: Linear,
    /// How the depthwise convolution is computed under autodiff (sampling has its own kernel
    /// for the same function, `MixFfn::sampling_middle`).
    #[module(skip)]
    pub how: Depthwise,
}

impl MixFfn {
    /// A new Mix-FFN of `width` with hidden width `hidden`.
    pub fn new(width: usize, hidden: usize, how: Depthwise, device: &Device) -> Self {
        Self {
            inverted: LinearConfig::new(width, 2 * hidden).init(device),
            depthwise: DepthwiseConv::new(2 * hidden, device),
            point: LinearConfig::new(hidden, width).init(device),
            how,
        }
    }

    /// `[B, N, C] -> [B, N, C]`, tokens in row-major order of a square `G x G` grid.
    pub fn forward(&self, x: Tensor<3>) -> Tensor<3> {
        let [b, n, _] = x.dims();
        let g = (n as f64).sqrt().round() as usize;
        let y = self.inverted.forward(x); // [B, N, 2H]
        if !y.device().is_autodiff() {
            return self.point.forward(self.sampling_middle(y, g));
        }
        let k = y.dims()[2];
        let grid = silu(y).swap_dims(1, 2).reshape([b, k, g, g]);
        let y = self
            .depthwise
            .forward(grid, self.how)
            .reshape([b, k, n])
            .swap_dims(1, 2);
        let hidden = k / 2;
        let value = y.clone().slice(s![.., .., 0..hidden]);
        let gate = y.slice(s![.., .., hidden..k]);
        self.point.forward(value * silu(gate))
    }

    /// The part between the two linears, `[B, N, 2H] -> [B, N, H]`, for sampling (outside
    /// autodiff): SiLU, the depthwise convolution and the gate in three passes over plain
    /// values, channels last throughout so every inner loop runs over contiguous channels and
    /// vectorizes. burn's `flex` backend makes about ten passes of it (sigmoid with scalar
    /// `expf`, products, two transposes, slices), and its sigmoid alone took 15% of a whole
    /// `predict` run (perf, 1 thread). The same function as the autodiff path (a test).
    fn sampling_middle(&self, y: Tensor<3>, g: usize) -> Tensor<3> {
        let [b, n, k] = y.dims();
        let device = y.device();
        let mut activated = f32_values(y);
        // Taps as [9][K] so a tap's weights over the channels are contiguous.
        let weight = f32_values(self.depthwise.weight.val());
        let taps: Vec<f32> = (0..9)
            .flat_map(|tap| (0..k).map(move |c| (tap, c)))
            .map(|(tap, c)| weight[c * 9 + tap])
            .collect();
        let bias = f32_values(self.depthwise.bias.val());
        let mut gated = vec![0.0f32; b * n * (k / 2)];
        super::kernels::silu_depthwise_gate(&mut activated, &taps, &bias, g, &mut gated);
        Tensor::from_data(TensorData::new(gated, [b, n, k / 2]), &device)
    }
}

fn f32_values<const D: usize>(t: Tensor<D>) -> Vec<f32> {
    t.into_data()
        .try_into_vec::<f32>()
        .expect("the model computes in f32")
}

#[cfg(test)]
pub(crate) mod tests {
    use super::*;
    use burn::tensor::Distribution;

    fn values(t: Tensor<4>) -> Vec<f32> {
        t.try_into_vec_as::<f32>().expect("f32 values")
    }

    #[test]
    fn shifted_depthwise_equals_conv2d() {
        let device = Device::flex();
        let _random = crate::seeded(&device, 3);
        let conv = DepthwiseConv::new(5, &device);
        let x = Tensor::<4>::random([2, 5, 6, 6], Distribution::Normal(0.0, 1.0), &device);
        let a = values(conv.forward(x.clone(), Depthwise::Shifted));
        let b = values(conv.forward(x, Depthwise::Conv2d));
        let worst = largest_difference(&a, &b);
        assert!(worst < 1e-5, "largest difference {worst}");
    }

    /// The largest absolute difference between two equally long lists of values.
    pub(crate) fn largest_difference(a: &[f32], b: &[f32]) -> f32 {
        assert_eq!(a.len(), b.len());
        a.iter()
            .zip(b)
            .map(|(a, b)| (a - b).abs())
            .fold(0.0, f32::max)
    }

    /// The autodiff gradient of `f` at `x` checked by central differences: along the gradient
    /// itself (relative error, where a wrong gradient shows as a wrong length or angle) and
    /// along random directions (error relative to |g| |d|; ReLU kinks make a tighter bound
    /// on single random directions meaningless in f32). Returns the worst errors of both.
    pub(crate) fn gradient_check(f: &dyn Fn(Tensor<3>) -> Tensor<1>, x: Tensor<3>) -> (f64, f64) {
        let plain = x.device();
        let device = plain.clone().autodiff();
        let xa = Tensor::<3>::from_data(x.to_data(), &device).require_grad();
        let g = xa.grad(&f(xa.clone()).backward()).expect("a gradient");
        let g = Tensor::<3>::from_data(g.to_data(), &plain);
        let norm = |t: &Tensor<3>| f64::from(t.clone().square().sum().into_scalar::<f32>()).sqrt();
        let along = |d: Tensor<3>| {
            let h = 1e-2 / norm(&d) as f32;
            let analytic = f64::from((g.clone() * d.clone()).sum().into_scalar::<f32>());
            let plus = f64::from(f(x.clone() + d.clone().mul_scalar(h)).into_scalar::<f32>());
            let minus = f64::from(f(x.clone() - d.mul_scalar(h)).into_scalar::<f32>());
            (analytic, (plus - minus) / (2.0 * f64::from(h)))
        };
        let (a, n) = along(g.clone());
        let relative = (a - n).abs() / n.abs().max(1e-12);
        let mut random: f64 = 0.0;
        for _ in 0..3 {
            let d = g.random_like(Distribution::Normal(0.0, 1.0));
            let scale = norm(&g) * norm(&d);
            let (a, n) = along(d);
            random = random.max((a - n).abs() / scale.max(1e-12));
        }
        (relative, random)
    }

    #[test]
    fn linear_attention_gradients_match_finite_differences() {
        let device = Device::flex();
        let _random = crate::seeded(&device, 5);
        let n = Distribution::Normal(0.0, 1.0);
        let attention = LinearAttention::new(8, 2, &device);
        let weights = Tensor::<3>::random([2, 6, 8], n, &device);
        let autodiff = attention.clone().train();
        let f = |x: Tensor<3>| {
            let model = if x.device().is_autodiff() {
                &autodiff
            } else {
                &attention
            };
            let w = Tensor::<3>::from_data(weights.to_data(), &x.device());
            (model.forward(x) * w).sum()
        };
        for k in 0..3 {
            let (along, random) = gradient_check(&f, Tensor::<3>::random([2, 6, 8], n, &device));
            assert!(
                along < 1e-2 && random < 1e-2,
                "draw {k}: errors {along:.2e} along the gradient, {random:.2e} across"
            );
        }
    }

    /// The fused one-pass Mix-FFN used in sampling computes what the autodiff path (burn's
    /// own SiLU, transposes and slices) computes.
    #[test]
    fn the_sampling_mix_ffn_equals_the_training_one() {
        let device = Device::flex();
        let _random = crate::seeded(&device, 6);
        let ffn = MixFfn::new(8, 20, Depthwise::Conv2d, &device);
        let x = Tensor::<3>::random([2, 16, 8], Distribution::Normal(0.0, 2.0), &device);
        let sampling: Vec<f32> = ffn.forward(x.clone()).try_into_vec_as().unwrap();
        let autodiff = device.clone().autodiff();
        let xa = Tensor::<3>::from_data(x.to_data(), &autodiff);
        let training: Vec<f32> = ffn.train().forward(xa).try_into_vec_as().unwrap();
        let worst = largest_difference(&sampling, &training);
        assert!(worst < 1e-5, "largest difference {worst}");
    }

    #[test]
    fn the_norm_has_zero_mean_and_unit_variance() {
        let device = Device::flex();
        let x = Tensor::<3>::from_data([[[1.0f32, 2.0, 3.0, 6.0]]], &device);
        let y: Vec<f32> = norm(x).try_into_vec_as::<f32>().unwrap();
        let mean = y.iter().sum::<f32>() / 4.0;
        let var = y.iter().map(|v| (v - mean).powi(2)).sum::<f32>() / 4.0;
        assert!(mean.abs() < 1e-6 && (var - 1.0).abs() < 1e-4, "{y:?}");
    }
}
