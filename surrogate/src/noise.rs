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

/// A smooth standard-normal field `[channels, r, r]` (channels first): a `cells` x `cells`
/// grid of draws per channel, bilinearly interpolated over the image. The error a network
/// makes on a whole garment is smooth like this, not texel by texel.
pub fn smooth_field(rng: &mut ChaCha8Rng, channels: usize, r: usize, cells: usize) -> Vec<f32> {
    let n = cells + 1;
    let mut out = Vec::with_capacity(channels * r * r);
    for _ in 0..channels {
        let grid: Vec<f32> = (0..n * n).map(|_| normal(rng)).collect();
        let at = |i: usize, j: usize| grid[i * n + j];
        for y in 0..r {
            let v = (y as f32 + 0.5) / r as f32 * cells as f32;
            let (i, fy) = ((v as usize).min(cells - 1), v.fract());
            for x in 0..r {
                let u = (x as f32 + 0.5) / r as f32 * cells as f32;
                let (j, fx) = ((u as usize).min(cells - 1), u.fract());
                let top = at(i, j) * (1.0 - fx) + at(i, j + 1) * fx;
                let bottom = at(i + 1, j) * (1.0 - fx) + at(i + 1, j + 1) * fx;
                out.push(top * (1.0 - fy) + bottom * fy);
            }
        }
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_smooth_field_is_smooth_and_seeded() {
        let field = smooth_field(&mut generator(3, 9, 0), 2, 32, 4);
        assert_eq!(field.len(), 2 * 32 * 32);
        assert_eq!(field, smooth_field(&mut generator(3, 9, 0), 2, 32, 4));
        // Neighbouring texels differ by far less than the field's spread (independent draws
        // would differ by about 1.4 times it).
        let spread = (field.iter().map(|v| v * v).sum::<f32>() / field.len() as f32).sqrt();
        let step = field[..32]
            .windows(2)
            .map(|w| (w[1] - w[0]).abs())
            .fold(0.0f32, f32::max);
        assert!(spread > 0.2, "spread {spread}");
        assert!(step < 0.5 * spread, "step {step} against spread {spread}");
        // The channels are drawn apart.
        assert_ne!(field[..1024], field[1024..]);
    }
}
