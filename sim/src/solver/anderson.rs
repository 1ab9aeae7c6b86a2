//! Anderson acceleration of a step's iteration (Walker and Ni 2011; Peng et al. 2018 apply it
//! to projective dynamics).
//!
//! One local-global iteration maps the iterate z = (v, r / m, r_pair / m_pair), the
//! velocities and the contact impulses per unit effective mass (every entry in m/s), to g(z).
//! Plain iteration takes z <- g(z); where the garment's weight rests on the body, a few dozen
//! contacts whose effective mass is ten times the node's own converge by about 7% per
//! iteration and hold the residual up (docs/BENCHMARKS.md). Accelerated, the next iterate is
//! g_k - dG gamma, with gamma minimizing |f_k - dF gamma| (f = g - z; dF, dG the differences
//! of the last `depth` iterations), a secant step over the iteration's own history. Mixed
//! impulses are projected back into their friction cones. The history restarts every step.
//!
//! Written by hand: the solve is a few lines over the solver's own vectors, and the crates
//! that implement it (argmin's, for one) own the iteration loop.

use super::Workspace;
use crate::cloth::Vec3;

/// The history and buffers of the acceleration (sized on first use, reused every step).
pub(super) struct Anderson {
    depth: usize,
    /// The iterate an iteration starts from; after `mix`, the accelerated one.
    z: Vec<f64>,
    /// f = g - z of the current iteration (scratch).
    f: Vec<f64>,
    /// g(z) of the current iteration (scratch).
    g: Vec<f64>,
    /// f and g of the last iteration.
    last_f: Vec<f64>,
    last_g: Vec<f64>,
    /// Ring of the last `depth` differences of f and of g.
    df: Vec<Vec<f64>>,
    dg: Vec<Vec<f64>>,
    /// dF^T dF by ring slot (`depth` x `depth`); a slot's row is computed when it is written.
    gram: Vec<f64>,
    /// The ring slot the next difference goes to.
    next: usize,
    /// Ring slots holding a difference.
    filled: usize,
    /// Whether `last_f` and `last_g` belong to this step.
    has_last: bool,
    /// Whether `z` holds the workspace's iterate (the last acceleration's, as scattered).
    z_ready: bool,
}

impl Anderson {
    /// Mixes up to `depth` past iterations (1 to [`MAX_DEPTH`]).
    pub fn new(depth: usize) -> Self {
        assert!((1..=MAX_DEPTH).contains(&depth), "depth {depth}");
        Self {
            depth,
            z: Vec::new(),
            f: Vec::new(),
            g: Vec::new(),
            last_f: Vec::new(),
            last_g: Vec::new(),
            df: vec![Vec::new(); depth],
            dg: vec![Vec::new(); depth],
            gram: vec![0.0; depth * depth],
            next: 0,
            filled: 0,
            has_last: false,
            z_ready: false,
        }
    }

    /// Forgets the history (a new step: new contacts, new unknowns).
    pub fn reset(&mut self) {
        self.filled = 0;
        self.next = 0;
        self.has_last = false;
        self.z_ready = false;
    }

    /// Stores the iterate before an iteration.
    pub fn begin(&mut self, ws: &Workspace) {
        if !self.z_ready {
            gather(ws, &mut self.z);
        }
    }

    /// After an iteration (`ws.v` holds g's velocities): the accelerated iterate, scattered
    /// back into the workspace (left as g while there is no history yet).
    pub fn accelerate(&mut self, ws: &mut Workspace) {
        gather(ws, &mut self.g);
        self.z_ready = self.mix();
        if self.z_ready {
            scatter(&mut self.z, ws);
        }
    }

    /// With `z` and `g = g(z)` filled: records the new differences and puts the accelerated
    /// iterate in `z`; false (and `z` unusable) when there is nothing to mix yet. Both passes
    /// over the vectors run on two fixed halves whose partial sums are added in a fixed
    /// order, so the result has the same bits on any thread count.
    fn mix(&mut self) -> bool {
        let n = self.g.len();
        self.f.resize(n, 0.0);
        let depth = self.depth;
        let slot = self.next;
        if self.has_last {
            self.filled = (self.filled + 1).min(depth);
            self.df[slot].resize(n, 0.0);
            self.dg[slot].resize(n, 0.0);
        }
        let (fresh, filled) = (self.has_last, self.filled);
        let mid = n / 2;
        let sums = {
            let (df_before, rest) = self.df.split_at_mut(slot);
            let (df_cur, df_after) = rest.split_first_mut().expect("slot < depth");
            let others: Vec<&[f64]> = df_before
                .iter()
                .map(Vec::as_slice)
                .chain(std::iter::once(&[][..]))
                .chain(df_after.iter().map(Vec::as_slice))
                .take(filled)
                .collect();
            let (f0, f1) = self.f.split_at_mut(mid);
            let (d0, d1) = if fresh {
                df_cur.split_at_mut(mid)
            } else {
                (&mut [][..], &mut [][..])
            };
            let (e0, e1) = if fresh {
                self.dg[slot].split_at_mut(mid)
            } else {
                (&mut [][..], &mut [][..])
            };
            let part =
                |range: std::ops::Range<usize>, f: &mut [f64], df: &mut [f64], dg: &mut [f64]| {
                    let ring: Vec<&[f64]> = others
                        .iter()
                        .map(|d| {
                            if d.is_empty() {
                                &[][..]
                            } else {
                                &d[range.clone()]
                            }
                        })
                        .collect();
                    update_half(
                        Half {
                            g: &self.g[range.clone()],
                            z: &self.z[range.clone()],
                            last_f: self.last_f.get(range.clone()).unwrap_or(&[]),
                            last_g: self.last_g.get(range).unwrap_or(&[]),
                        },
                        f,
                        df,
                        dg,
                        &ring,
                        slot,
                    )
                };
            let (a, b) =
                crate::spin_join::join(|| part(0..mid, f0, d0, e0), || part(mid..n, f1, d1, e1));
            let mut sums = [0.0; 2 * MAX_DEPTH];
            for (s, (x, y)) in sums.iter_mut().zip(a.iter().zip(&b)) {
                *s = x + y;
            }
            sums
        };
        if fresh {
            for (q, &sum) in sums[..filled].iter().enumerate() {
                self.gram[slot * depth + q] = sum;
                self.gram[q * depth + slot] = sum;
            }
            self.next = (slot + 1) % depth;
        }
        std::mem::swap(&mut self.last_f, &mut self.f);
        std::mem::swap(&mut self.last_g, &mut self.g);
        self.has_last = true;
        let m = filled;
        if m == 0 {
            return false;
        }
        // Normal equations (dF^T dF + lambda I) gamma = dF^T f over the filled slots; the
        // small ridge keeps them solvable when differences repeat (a converged contact set).
        let mut a = [0.0; MAX_DEPTH * MAX_DEPTH];
        let mut b = [0.0; MAX_DEPTH];
        for p in 0..m {
            for q in 0..m {
                a[p * m + q] = self.gram[p * depth + q];
            }
            b[p] = sums[MAX_DEPTH + p];
        }
        let trace: f64 = (0..m).map(|p| a[p * m + p]).sum();
        if !trace.is_finite() || trace <= 0.0 {
            return false;
        }
        for p in 0..m {
            a[p * m + p] += 1e-8 * trace;
        }
        let Some(gamma) = solve(&mut a[..m * m], &mut b[..m], m) else {
            return false;
        };
        // z = g - dG gamma, into `z` (free until the next `begin`).
        self.z.resize(n, 0.0);
        let (z0, z1) = self.z.split_at_mut(mid);
        let (g, dg) = (&self.last_g, &self.dg[..m]);
        let blend = |z: &mut [f64], lo: usize| {
            z.copy_from_slice(&g[lo..lo + z.len()]);
            for (p, gp) in gamma.iter().enumerate() {
                for (zi, d) in z.iter_mut().zip(&dg[p][lo..]) {
                    *zi -= gp * d;
                }
            }
        };
        crate::spin_join::join(|| blend(z0, 0), || blend(z1, mid));
        true
    }
}

/// The most differences kept.
const MAX_DEPTH: usize = crate::params::MAX_ACCELERATION;

/// One half's iterate, its image, and the last iteration's f and g.
struct Half<'a> {
    g: &'a [f64],
    z: &'a [f64],
    last_f: &'a [f64],
    last_g: &'a [f64],
}

/// f = g - z over one half; with a last iteration (`df` not empty), the new differences
/// df = f - f_last and dg = g - g_last, and the half's partial sums: df . df_q for every
/// filled slot q (the new slot `slot` is `df` itself) in [0, MAX_DEPTH), df_p . f after.
fn update_half(
    half: Half,
    f: &mut [f64],
    df: &mut [f64],
    dg: &mut [f64],
    ring: &[&[f64]],
    slot: usize,
) -> [f64; 2 * MAX_DEPTH] {
    for ((f, g), z) in f.iter_mut().zip(half.g).zip(half.z) {
        *f = g - z;
    }
    let mut sums = [0.0; 2 * MAX_DEPTH];
    if df.is_empty() {
        return sums;
    }
    for ((d, f), last) in df.iter_mut().zip(&*f).zip(half.last_f) {
        *d = f - last;
    }
    for ((d, g), last) in dg.iter_mut().zip(half.g).zip(half.last_g) {
        *d = g - last;
    }
    for (q, other) in ring.iter().enumerate() {
        let other = if q == slot { &*df } else { other };
        sums[q] = dot(df, other);
        sums[MAX_DEPTH + q] = dot(other, f);
    }
    sums
}

/// Dot product in four interleaved partial sums (vectorizes; a fixed order, so the same bits
/// every time).
fn dot(a: &[f64], b: &[f64]) -> f64 {
    let mut lanes = [0.0; 4];
    let (ca, cb) = (a.chunks_exact(4), b.chunks_exact(4));
    let tail: f64 = ca
        .remainder()
        .iter()
        .zip(cb.remainder())
        .map(|(x, y)| x * y)
        .sum();
    for (x, y) in ca.zip(cb) {
        for l in 0..4 {
            lanes[l] += x[l] * y[l];
        }
    }
    (lanes[0] + lanes[1]) + (lanes[2] + lanes[3]) + tail
}

/// Gaussian elimination with partial pivoting of a small dense system; `None` if singular.
fn solve(a: &mut [f64], b: &mut [f64], m: usize) -> Option<Vec<f64>> {
    for col in 0..m {
        let pivot =
            (col..m).max_by(|&i, &j| a[i * m + col].abs().total_cmp(&a[j * m + col].abs()))?;
        if a[pivot * m + col].abs() < 1e-300 {
            return None;
        }
        if pivot != col {
            for k in 0..m {
                a.swap(pivot * m + k, col * m + k);
            }
            b.swap(pivot, col);
        }
        for row in col + 1..m {
            let factor = a[row * m + col] / a[col * m + col];
            for k in col..m {
                a[row * m + k] -= factor * a[col * m + k];
            }
            b[row] -= factor * b[col];
        }
    }
    let mut x = vec![0.0; m];
    for row in (0..m).rev() {
        let mut s = b[row];
        for k in row + 1..m {
            s -= a[row * m + k] * x[k];
        }
        x[row] = s / a[row * m + row];
    }
    x.iter().all(|v| v.is_finite()).then_some(x)
}

/// Appends `v * scale` as three entries.
fn push(out: &mut Vec<f64>, v: Vec3, scale: f64) {
    out.extend([v.x * scale, v.y * scale, v.z * scale]);
}

/// The iterate of the workspace: velocities, then impulses per unit effective mass.
fn gather(ws: &Workspace, out: &mut Vec<f64>) {
    out.clear();
    for v in &ws.v {
        push(out, *v, 1.0);
    }
    for (r, m) in ws.impulses.iter().zip(&ws.effective_mass) {
        push(out, *r, 1.0 / m);
    }
    for (r, m) in ws.self_impulses.iter().zip(&ws.self_mass) {
        push(out, *r, 1.0 / m);
    }
}

/// Entry k of a vector of `Vec3`s times `scale`.
fn read(z: &[f64], k: usize, scale: f64) -> Vec3 {
    Vec3::new(z[3 * k] * scale, z[3 * k + 1] * scale, z[3 * k + 2] * scale)
}

/// Sets entry k of a vector of `Vec3`s.
fn write(z: &mut [f64], k: usize, v: Vec3) {
    z[3 * k..3 * k + 3].copy_from_slice(&[v.x, v.y, v.z]);
}

/// Impulse `r` brought into the cone of normal `n` and coefficient `mu`: the normal part
/// clamped at zero, then the tangential part scaled to the rim (the cone's radial
/// projection, not the Euclidean one: cheaper, and it keeps r's direction in the plane).
fn into_cone(r: Vec3, n: Vec3, mu: f64) -> Vec3 {
    let r_n = r.dot(&n).max(0.0);
    let mut r_t = r - r.dot(&n) * n;
    let norm = r_t.norm();
    if norm > mu * r_n {
        r_t *= if norm > 0.0 { mu * r_n / norm } else { 0.0 };
    }
    r_n * n + r_t
}

/// Writes iterate `z` into the workspace, and the impulses as projected back into `z`.
fn scatter(z: &mut [f64], ws: &mut Workspace) {
    let nv = ws.v.len();
    for (k, v) in ws.v.iter_mut().enumerate() {
        *v = read(z, k, 1.0);
    }
    for (k, (r, m)) in ws.impulses.iter_mut().zip(&ws.effective_mass).enumerate() {
        let c = &ws.contacts[k];
        *r = into_cone(read(z, nv + k, *m), c.normal, c.friction);
        write(z, nv + k, *r / *m);
    }
    let nc = nv + ws.impulses.len();
    for (k, (r, m)) in ws.self_impulses.iter_mut().zip(&ws.self_mass).enumerate() {
        let c = &ws.self_contacts[k];
        *r = into_cone(read(z, nc + k, *m), c.normal, c.friction);
        write(z, nc + k, *r / *m);
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A linear contraction g(z) = A z + b, A = D + coupling of neighbours, with factors up to
    /// 0.97 (plain iteration needs hundreds of iterations, like the slow contacts).
    fn contraction(z: &[f64]) -> Vec<f64> {
        let n = z.len();
        (0..n)
            .map(|i| {
                let own = 0.5 + 0.47 * (i as f64 / n as f64);
                let next = if i + 1 < n { z[i + 1] } else { 0.0 };
                own * z[i] + 0.01 * next + (i % 5) as f64
            })
            .collect()
    }

    fn fixed_point_error(z: &[f64]) -> f64 {
        contraction(z)
            .iter()
            .zip(z)
            .map(|(g, z)| (g - z).abs())
            .fold(0.0, f64::max)
    }

    /// `iterations` iterations from zero, accelerated over `depth` (0: plain).
    fn iterate(depth: usize, iterations: usize) -> Vec<f64> {
        let n = 101;
        if depth == 0 {
            let mut z = vec![0.0; n];
            for _ in 0..iterations {
                z = contraction(&z);
            }
            return z;
        }
        let mut a = Anderson::new(depth);
        a.z = vec![0.0; n];
        for _ in 0..iterations {
            a.g = contraction(&a.z);
            if !a.mix() {
                a.z.clone_from(&a.last_g);
            }
        }
        a.z
    }

    #[test]
    fn converges_where_plain_iteration_crawls() {
        let plain = fixed_point_error(&iterate(0, 30));
        let accelerated = fixed_point_error(&iterate(5, 30));
        assert!(plain > 0.1, "plain {plain}");
        assert!(
            accelerated < 1e-3 * plain,
            "accelerated {accelerated}, plain {plain}"
        );
    }

    #[test]
    fn same_bits_on_any_thread_count() {
        let helper = iterate(3, 12);
        for threads in [1, 2] {
            let pool = rayon::ThreadPoolBuilder::new()
                .num_threads(threads)
                .build()
                .unwrap();
            assert_eq!(helper, pool.install(|| iterate(3, 12)), "{threads} threads");
        }
    }

    #[test]
    fn mixed_impulses_stay_in_their_cone() {
        let n = Vec3::new(0.0, 1.0, 0.0);
        for r in [
            Vec3::new(3.0, -1.0, 0.0),
            Vec3::new(3.0, 1.0, 4.0),
            Vec3::new(0.1, 1.0, 0.0),
        ] {
            let p = into_cone(r, n, 0.3);
            let (r_n, r_t) = (p.dot(&n), (p - p.dot(&n) * n).norm());
            assert!(r_n >= 0.0 && r_t <= 0.3 * r_n + 1e-15, "{r:?} -> {p:?}");
        }
        assert_eq!(
            into_cone(Vec3::new(0.1, 1.0, 0.0), n, 0.3),
            Vec3::new(0.1, 1.0, 0.0),
            "inside the cone: unchanged"
        );
    }
}
