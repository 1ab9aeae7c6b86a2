//! The one hand-written numeric kernel of the model: the middle of the Mix-FFN in sampling
//! (SiLU, the 3 x 3 depthwise convolution over the token grid, the gate), with the
//! vectorizable `exp` it needs. It is compiled twice, portable and for AVX2, and picked at run
//! time (`is_x86_feature_detected!`); both clones are public to the crate so a test can run
//! each on the same input and compare them bit for bit. Written by hand because burn's `flex`
//! backend makes about ten passes of this function (`MixFfn::sampling_middle`), and no crate
//! offers a vectorizing f32 `exp` on stable Rust without a SIMD framework.

/// The Mix-FFN's middle in sampling: `values` `[B, G * G, K]` (overwritten with their SiLU),
/// `taps` `[9, K]`, `bias` `[K]` -> `gated` `[B, G * G, K / 2]`. The AVX2 clone where the CPU
/// has it, else the portable one: the same operations in the same order, eight lanes instead
/// of four, so the results are identical (`both_clones_agree_bit_for_bit`).
pub(crate) fn silu_depthwise_gate(
    values: &mut [f32],
    taps: &[f32],
    bias: &[f32],
    g: usize,
    gated: &mut [f32],
) {
    #[cfg(target_arch = "x86_64")]
    if std::arch::is_x86_feature_detected!("avx2") {
        // SAFETY: the CPU has AVX2, checked just above.
        return unsafe { silu_depthwise_gate_avx2(values, taps, bias, g, gated) };
    }
    silu_depthwise_gate_portable(values, taps, bias, g, gated)
}

/// The portable clone (the target's baseline features).
pub(crate) fn silu_depthwise_gate_portable(
    values: &mut [f32],
    taps: &[f32],
    bias: &[f32],
    g: usize,
    gated: &mut [f32],
) {
    silu_depthwise_gate_body(values, taps, bias, g, gated)
}

/// The AVX2 clone: the body inlined into a function compiled with AVX2 enabled.
#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx2")]
pub(crate) fn silu_depthwise_gate_avx2(
    values: &mut [f32],
    taps: &[f32],
    bias: &[f32],
    g: usize,
    gated: &mut [f32],
) {
    silu_depthwise_gate_body(values, taps, bias, g, gated)
}

#[inline(always)]
fn silu_depthwise_gate_body(
    values: &mut [f32],
    taps: &[f32],
    bias: &[f32],
    g: usize,
    gated: &mut [f32],
) {
    let (n, k) = (g * g, bias.len());
    let hidden = k / 2;
    for v in values.iter_mut() {
        *v = silu_value(*v);
    }
    let mut sum = vec![0.0f32; k];
    for (src, dst) in values
        .chunks_exact(n * k)
        .zip(gated.chunks_exact_mut(n * hidden))
    {
        for (token, out) in dst.chunks_exact_mut(hidden).enumerate() {
            let (row, col) = (token / g, token % g);
            sum.copy_from_slice(bias);
            for (tap, w) in taps.chunks_exact(k).enumerate() {
                let (r, c) = (
                    (row + tap / 3).wrapping_sub(1),
                    (col + tap % 3).wrapping_sub(1),
                );
                if r >= g || c >= g {
                    continue; // zero padding
                }
                let neighbour = &src[(r * g + c) * k..][..k];
                for ((s, &w), &x) in sum.iter_mut().zip(w).zip(neighbour) {
                    *s += w * x;
                }
            }
            let (value, gate) = sum.split_at(hidden);
            for ((o, &v), &gt) in out.iter_mut().zip(value).zip(gate) {
                *o = v * silu_value(gt);
            }
        }
    }
}

/// x * sigmoid(x) = x / (1 + e^-x).
#[inline(always)]
fn silu_value(x: f32) -> f32 {
    x / (1.0 + exp_vectorizable(-x))
}

/// e^x with no call into libm and no branch, so loops over it vectorize: Cody-Waite reduction
/// x = n ln 2 + r, |r| <= ln 2 / 2, and the degree-6 Taylor polynomial of e^r (truncation
/// below 1.3e-7 relative). Inputs are clamped to [-87.3, 88.3], where 2^n stays a normal f32;
/// SiLU only needs e^-x to saturate there. No crate offers a vectorizing f32 exp on stable
/// Rust without a SIMD framework, which is why it is written here.
#[inline(always)]
fn exp_vectorizable(x: f32) -> f32 {
    const LN2_HI: f32 = 0.693_145_75;
    const LN2_LO: f32 = 1.428_606_8e-6;
    // Adding 1.5 * 2^23 rounds to the nearest integer without a branch and leaves that
    // integer in the low bits, so 2^n is built with integer adds and a shift (a float-to-int
    // `as` cast saturates lane by lane and stops the loop from vectorizing).
    const ROUND: f32 = 12_582_912.0;
    let x = x.clamp(-87.3, 88.3);
    let shifted = x * std::f32::consts::LOG2_E + ROUND;
    let n = shifted - ROUND;
    let r = x - n * LN2_HI - n * LN2_LO;
    let p = 1.0
        + r * (1.0
            + r * (0.5 + r * (1.0 / 6.0 + r * (1.0 / 24.0 + r * (1.0 / 120.0 + r / 720.0)))));
    let two_to_n = (shifted
        .to_bits()
        .wrapping_sub(ROUND.to_bits())
        .wrapping_add(127))
        << 23;
    f32::from_bits(two_to_n) * p
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_vectorizable_exp_matches_libm() {
        let mut worst: f32 = 0.0;
        for i in -87_000..=88_000 {
            let x = i as f32 * 1e-3;
            let (fast, libm) = (exp_vectorizable(x), x.exp());
            worst = worst.max((fast - libm).abs() / libm);
        }
        assert!(worst < 5e-7, "largest relative error {worst:e}");
        assert_eq!(exp_vectorizable(-200.0), (-87.3f32).exp());
        assert!(silu_value(-200.0).abs() < 1e-30 && silu_value(200.0) == 200.0);
    }

    /// The portable and the AVX2 clones give the same bits (the dispatcher runs only one of
    /// them on any machine, so without this the other would never run in the tests).
    #[test]
    fn both_clones_agree_bit_for_bit() {
        let (b, g, k) = (2, 5, 12);
        let mut draw = 0.37f32;
        let mut next = move || {
            draw = (draw * 3.9 * (1.0 - draw)).clamp(0.01, 0.99);
            (draw - 0.5) * 8.0
        };
        let values: Vec<f32> = (0..b * g * g * k).map(|_| next()).collect();
        let taps: Vec<f32> = (0..9 * k).map(|_| next()).collect();
        let bias: Vec<f32> = (0..k).map(|_| next()).collect();
        let run = |kernel: &dyn Fn(&mut [f32], &mut [f32])| {
            let (mut v, mut out) = (values.clone(), vec![0.0f32; b * g * g * k / 2]);
            kernel(&mut v, &mut out);
            (v, out)
        };
        let portable = run(&|v, out| silu_depthwise_gate_portable(v, &taps, &bias, g, out));
        let dispatched = run(&|v, out| silu_depthwise_gate(v, &taps, &bias, g, out));
        let bits = |x: &[f32]| x.iter().map(|v| v.to_bits()).collect::<Vec<_>>();
        assert!(portable.1.iter().any(|v| *v != 0.0));
        assert_eq!(bits(&portable.0), bits(&dispatched.0));
        assert_eq!(bits(&portable.1), bits(&dispatched.1));
        #[cfg(target_arch = "x86_64")]
        if std::arch::is_x86_feature_detected!("avx2") {
            // SAFETY: the CPU has AVX2.
            let avx2 = run(&|v, out| unsafe { silu_depthwise_gate_avx2(v, &taps, &bias, g, out) });
            assert_eq!(bits(&portable.0), bits(&avx2.0));
            assert_eq!(bits(&portable.1), bits(&avx2.1));
        } else {
            eprintln!("no AVX2 on this CPU: only the portable clone ran");
        }
    }
}
