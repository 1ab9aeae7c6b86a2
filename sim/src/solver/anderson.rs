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
        self.differences(fresh, slot);
        let sums = if fresh {
            self.gram_sums(slot, filled)
        } else {
            [0.0; 2 * MAX_DEPTH]
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
        if filled == 0 {
            return false;
        }
        let Some(gamma) = self.mixing_weights(filled, &sums[MAX_DEPTH..MAX_DEPTH + filled]) else {
            return false;
        };
        self.blend(&gamma);
        true
    }

    /// f = g - z, and (when `fresh`) the new differences of f and g in `slot`, on two halves.
    fn differences(&mut self, fresh: bool, slot: usize) {
        let mid = self.g.len() / 2;
        let (g, z) = (&self.g, &self.z);
        let (last_f, last_g) = (&self.last_f, &self.last_g);
        let (f0, f1) = self.f.split_at_mut(mid);
        let (d0, d1) = self.df[slot].split_at_mut(if fresh { mid } else { 0 });
        let (e0, e1) = self.dg[slot].split_at_mut(if fresh { mid } else { 0 });
        let differences = |lo: usize, f: &mut [f64], df: &mut [f64], dg: &mut [f64]| {
            let hi = lo + f.len();
            for ((f, g), z) in f.iter_mut().zip(&g[lo..hi]).zip(&z[lo..hi]) {
                *f = g - z;
            }
            if fresh {
                for ((d, f), last) in df.iter_mut().zip(&*f).zip(&last_f[lo..hi]) {
                    *d = f - last;
                }
                for ((d, g), last) in dg.iter_mut().zip(&g[lo..hi]).zip(&last_g[lo..hi]) {
                    *d = g - last;
                }
            }
        };
        crate::spin_join::join(
            || differences(0, f0, d0, e0),
            || differences(mid, f1, d1, e1),
        );
    }

    /// The new difference (in `slot`) against every filled slot (the Gram row, first
    /// MAX_DEPTH values), and every slot against f (the rest): per half, the halves' sums
    /// added in a fixed order.
    fn gram_sums(&self, slot: usize, filled: usize) -> [f64; 2 * MAX_DEPTH] {
        let (n, mid) = (self.f.len(), self.f.len() / 2);
        let (df, f) = (&self.df[..filled], &self.f);
        let partial = |range: std::ops::Range<usize>| {
            let mut sums = [0.0; 2 * MAX_DEPTH];
            let new = &df[slot][range.clone()];
            for (q, other) in df.iter().enumerate() {
                let other = &other[range.clone()];
                sums[q] = dot(new, other);
                sums[MAX_DEPTH + q] = dot(other, &f[range.clone()]);
            }
            sums
        };
        let (a, b) = crate::spin_join::join(|| partial(0..mid), || partial(mid..n));
        let mut sums = [0.0; 2 * MAX_DEPTH];
        for (s, (x, y)) in sums.iter_mut().zip(a.iter().zip(&b)) {
            *s = x + y;
        }
        sums
    }

    /// gamma from the normal equations (dF^T dF + lambda I) gamma = dF^T f over the `m`
    /// filled slots (`df_f` = dF^T f); the small ridge keeps them positive definite when
    /// differences repeat (a converged contact set). None when they cannot be solved.
    fn mixing_weights(&self, m: usize, df_f: &[f64]) -> Option<nalgebra::DVector<f64>> {
        let depth = self.depth;
        let gram = nalgebra::DMatrix::from_fn(m, m, |p, q| self.gram[p * depth + q]);
        let trace = gram.trace();
        if !trace.is_finite() || trace <= 0.0 {
            return None;
        }
        let ridged = gram + nalgebra::DMatrix::identity(m, m) * (1e-8 * trace);
        let gamma = ridged
            .cholesky()?
            .solve(&nalgebra::DVector::from_column_slice(df_f));
        gamma.iter().all(|g| g.is_finite()).then_some(gamma)
    }

    /// z = g - dG gamma, into `z` (free until the next `begin`), on two halves.
    fn blend(&mut self, gamma: &nalgebra::DVector<f64>) {
        let n = self.last_g.len();
        let mid = n / 2;
        self.z.resize(n, 0.0);
        let (z0, z1) = self.z.split_at_mut(mid);
        let (g, dg) = (&self.last_g, &self.dg[..gamma.len()]);
        let blend = |z: &mut [f64], lo: usize| {
            z.copy_from_slice(&g[lo..lo + z.len()]);
            for (p, gp) in gamma.iter().enumerate() {
                for (zi, d) in z.iter_mut().zip(&dg[p][lo..]) {
                    *zi -= gp * d;
                }
            }
        };
        crate::spin_join::join(|| blend(z0, 0), || blend(z1, mid));
    }
}

/// The most differences kept.
const MAX_DEPTH: usize = crate::params::MAX_ACCELERATION;

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
