//! The DiT's speed on this CPU: training samples/s and forward ms at 64 x 64 for patch 1, 2 and
//! 4 at batch 1, 16 and 64, on 1 and 2 threads, and the depthwise convolution as shifted
//! multiply-adds versus burn's grouped `Conv2d` in training (the only place the choice applies:
//! sampling always runs the hand-written kernel, `model/kernels.rs`, so a forward pass outside
//! autodiff would time that one kernel twice). Prints a markdown table
//! (`cargo bench -p surrogate --bench dit`; docs/BENCHMARKS.md records it).
//!
//! A training step is the trainer's: forward, weighted MSE, backward, global-norm clipping,
//! AdamW. Combinations over 65,536 tokens per batch are skipped (training: their activations
//! need tens of GB; forward: a minute a pass, and the trend is clear by then).

use std::time::Instant;

use burn::optim::GradientsParams;
use burn::prelude::*;
use burn::tensor::Distribution;
use surrogate::model::{Depthwise, Dit, DitConfig};
use surrogate::run::TrainConfig;
use surrogate::train::clip_global_norm;

/// A batch of `b` random inputs for `config`: noisy target, texel inputs (the position map and,
/// with body inputs, the skinned base and its change), mask, time, conditions.
fn inputs(b: usize, config: &DitConfig) -> (Tensor<4>, Tensor<4>, Tensor<4>, Tensor<1>, Tensor<2>) {
    let device = Device::flex();
    let n = Distribution::Normal(0.0, 1.0);
    let (r, d) = (config.resolution, config.condition_dim);
    (
        Tensor::random([b, 3, r, r], n, &device),
        Tensor::random([b, config.texel_channels(), r, r], n, &device),
        Tensor::ones([b, 1, r, r], &device),
        Tensor::random([b], Distribution::Default, &device),
        Tensor::random([b, d], n, &device),
    )
}

/// Median seconds of `reps` runs of `f` after one warm-up run.
fn time(reps: usize, mut f: impl FnMut()) -> f64 {
    f();
    let mut t: Vec<f64> = (0..reps)
        .map(|_| {
            let start = Instant::now();
            f();
            start.elapsed().as_secs_f64()
        })
        .collect();
    t.sort_by(f64::total_cmp);
    t[t.len() / 2]
}

fn forward_ms(config: &DitConfig, batch: usize) -> f64 {
    let device = Device::flex();
    device.seed(0);
    let model = Dit::new(config, &device);
    let (x, p, m, s, c) = inputs(batch, config);
    let reps = if batch >= 16 { 2 } else { 5 };
    1e3 * time(reps, || {
        let out = model.forward(x.clone(), p.clone(), m.clone(), s.clone(), c.clone());
        let _ = out.into_data();
    })
}

fn train_samples_per_s(config: &DitConfig, batch: usize) -> f64 {
    let device = Device::flex().autodiff();
    device.seed(0);
    let training = TrainConfig::default();
    let mut model = Some(Dit::new(config, &device));
    let mut optim = burn::optim::AdamWConfig::new()
        .with_epsilon(1e-8)
        .with_weight_decay(1e-2)
        .init();
    let (x, p, m, s, c) = inputs(batch, config);
    let target = x.clone();
    let seconds = time(2, || {
        let current = model.take().expect("a model");
        let out = current.forward(x.clone(), p.clone(), m.clone(), s.clone(), c.clone());
        let loss = (out - target.clone()).square().mean();
        let mut grads = GradientsParams::from_grads(loss.backward(), &current);
        clip_global_norm(&current, &mut grads, training.grad_clip_norm);
        model = Some(optim.step(training.lr, current, grads));
    });
    batch as f64 / seconds
}

fn main() {
    let filter: Option<String> = std::env::args().skip(1).find(|a| !a.starts_with('-'));
    let base = DitConfig::default();
    println!(
        "DiT {r}x{r}, width {}, depth {}, heads {}, {} condition tokens; `cargo bench -p surrogate --bench dit`",
        base.width,
        base.depth,
        base.heads,
        base.condition_tokens,
        r = base.resolution,
    );
    println!("| threads | patch | tokens | parameters | batch | forward ms | train samples/s |");
    println!("|---|---|---|---|---|---|---|");
    for threads in [1, 2] {
        let pool = rayon::ThreadPoolBuilder::new()
            .num_threads(threads)
            .build()
            .expect("a pool");
        for patch in [4, 2, 1] {
            let config = DitConfig {
                patch,
                ..base.clone()
            };
            let tokens = config.grid() * config.grid();
            let parameters = Dit::new(&config, &Device::flex()).parameters();
            for batch in [1, 16, 64] {
                let label = format!("t{threads}-p{patch}-b{batch}");
                if filter.as_ref().is_some_and(|f| !label.contains(f.as_str())) {
                    continue;
                }
                let forward = pool.install(|| forward_ms(&config, batch));
                let train = if batch * tokens <= 65_536 {
                    format!(
                        "{:.2}",
                        pool.install(|| train_samples_per_s(&config, batch))
                    )
                } else {
                    "skipped (memory)".into()
                };
                println!(
                    "| {threads} | {patch} | {tokens} | {parameters} | {batch} | {forward:.1} | {train} |"
                );
            }
        }
    }
    println!();
    println!("| depthwise (training only) | patch | batch | train samples/s |");
    println!("|---|---|---|---|");
    let pool = rayon::ThreadPoolBuilder::new()
        .num_threads(1)
        .build()
        .expect("a pool");
    for patch in [4, 2] {
        for how in [Depthwise::Shifted, Depthwise::Conv2d] {
            if filter.as_ref().is_some_and(|f| !f.contains("depthwise")) {
                continue;
            }
            let config = DitConfig {
                depthwise: how,
                patch,
                ..base.clone()
            };
            let train = pool.install(|| train_samples_per_s(&config, 16));
            println!("| {how:?} | {patch} | 16 | {train:.2} |");
        }
    }
}
