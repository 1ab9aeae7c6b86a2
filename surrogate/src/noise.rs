//! The seeded noise of training batches and of sampling: a ChaCha stream per (seed, purpose,
//! step), and standard normal draws from it by Box-Muller (a few lines; burn's own RNG is one
//! global state and would tie the draws to program order).

use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;

/// A generator for `purpose` at `step` of the run seeded by `seed`.
pub fn generator(seed: u64, purpose: u64, step: u64) -> ChaCha8Rng {
    let mut rng = ChaCha8Rng::seed_from_u64(seed);
    rng.set_stream(purpose);
    rng.set_word_pos(u128::from(step) << 32);
    rng
}

/// A standard normal draw.
pub fn normal(rng: &mut ChaCha8Rng) -> f32 {
    let u1: f64 = rng.random::<f64>().max(1e-300);
    let u2: f64 = rng.random();
    ((-2.0 * u1.ln()).sqrt() * (std::f64::consts::TAU * u2).cos()) as f32
}
