//! The comparison metrics of DiT-Garment / D-Garment (../shared/brief/METRICS.md), one
//! implementation for the regression suite, `compare` and the surrogate's evaluation.
//!
//! Units: E_v, E_CD_cm, E_d in cm; E_CD in 100 m^2 (squared distances, pytorch3d convention);
//! E_n dimensionless; E_c and E_c_vertex in %; E_b in rad; E_s dimensionless (x 1e5).
//! Surface samples: 50,000 area-uniform points per mesh with their face normals, from a seeded
//! ChaCha8 generator (the same stream for prediction and ground truth, so identical meshes
//! score exactly 0; the seed changes per frame); nearest neighbours from kiddo's k-d tree.
//! E_CD_cm is 100 x the mean of the two directions' mean nearest distances.

use kiddo::SquaredEuclidean;
use kiddo::immutable::float::kdtree::ImmutableKdTree;
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;
use serde::{Deserialize, Serialize};

/// Surface samples per mesh.
pub const SAMPLES: usize = 50_000;
/// Score every this many frames.
pub const FRAME_STRIDE: usize = 5;

type P3 = [f64; 3];

mod capture;
mod compare;
pub use capture::{
    CaptureCompared, CaptureScores, NOT_APPLICABLE, capture_frames, compare_with_capture,
    read_capture_frame, score_frame as score_capture_frame,
};
pub use compare::{Compared, compare, compare_recordings};
type Tree = ImmutableKdTree<f64, u32, 3, 32>;

fn sub(a: P3, b: P3) -> P3 {
    [a[0] - b[0], a[1] - b[1], a[2] - b[2]]
}
fn dot(a: P3, b: P3) -> f64 {
    a[0] * b[0] + a[1] * b[1] + a[2] * b[2]
}
fn cross(a: P3, b: P3) -> P3 {
    [
        a[1] * b[2] - a[2] * b[1],
        a[2] * b[0] - a[0] * b[2],
        a[0] * b[1] - a[1] * b[0],
    ]
}
fn norm(a: P3) -> f64 {
    dot(a, a).sqrt()
}

/// Scores of one frame (or their mean over frames).
#[derive(Debug, Clone, Copy, Default, PartialEq, Serialize, Deserialize)]
#[allow(non_snake_case)]
pub struct Scores {
    /// Mean vertex distance, cm.
    pub E_v: f64,
    /// Chamfer distance with squared distances x 100 (unit 100 m^2).
    pub E_CD: f64,
    /// Symmetric mean nearest-sample distance, cm.
    pub E_CD_cm: f64,
    /// Normal consistency: sum over both directions of mean (1 - |cos|).
    pub E_n: f64,
    /// Garment surface samples inside the body, %.
    pub E_c: f64,
    /// Garment vertices inside the body, %.
    pub E_c_vertex: f64,
    /// RMS dihedral-angle difference over interior edges, rad.
    pub E_b: f64,
    /// Strain-energy proxy difference x 1e5.
    pub E_s: f64,
    /// Area-weighted centroid distance, cm.
    pub E_d: f64,
}

impl Scores {
    /// Every score's key with its unit, in the order of [`Scores::values`].
    pub const UNITS: [(&str, &str); 9] = [
        ("E_v", "cm"),
        ("E_CD", "100 m^2 (squared distances)"),
        ("E_CD_cm", "cm"),
        ("E_n", "1 (sum of both directions)"),
        ("E_c", "% of garment surface samples inside the body"),
        (
            "E_c_vertex",
            "% of garment vertices inside the body (nearest body sample)",
        ),
        ("E_b", "rad"),
        ("E_s", "1 (x 1e5)"),
        ("E_d", "cm"),
    ];

    /// The scores in the order of [`Scores::UNITS`].
    pub fn values(&self) -> [f64; 9] {
        [
            self.E_v,
            self.E_CD,
            self.E_CD_cm,
            self.E_n,
            self.E_c,
            self.E_c_vertex,
            self.E_b,
            self.E_s,
            self.E_d,
        ]
    }

    fn add(&mut self, o: &Scores, w: f64) {
        self.E_v += w * o.E_v;
        self.E_CD += w * o.E_CD;
        self.E_CD_cm += w * o.E_CD_cm;
        self.E_n += w * o.E_n;
        self.E_c += w * o.E_c;
        self.E_c_vertex += w * o.E_c_vertex;
        self.E_b += w * o.E_b;
        self.E_s += w * o.E_s;
        self.E_d += w * o.E_d;
    }

    /// Mean of several frames' scores.
    pub fn mean(frames: &[Scores]) -> Scores {
        let mut m = Scores::default();
        for f in frames {
            m.add(f, 1.0 / frames.len().max(1) as f64);
        }
        m
    }
}

/// Jitter of a vertex sequence, cm: the mean over frames 1..n-1 and vertices of the second
/// difference |x_{k+1} - 2 x_k + x_{k-1}| (0 for fewer than 3 frames). A simulation's own
/// jitter is the reference a prediction's is read against.
pub fn jitter(frames: &[Vec<P3>]) -> f64 {
    let (mut sum, mut count) = (0.0, 0usize);
    for w in frames.windows(3) {
        for ((a, b), c) in w[0].iter().zip(&w[1]).zip(&w[2]) {
            sum += norm([
                c[0] - 2.0 * b[0] + a[0],
                c[1] - 2.0 * b[1] + a[1],
                c[2] - 2.0 * b[2] + a[2],
            ]);
            count += 1;
        }
    }
    100.0 * sum / count.max(1) as f64
}

/// Area-uniform samples of a mesh with their face normals.
pub struct SurfaceSamples {
    /// Points, m.
    pub points: Vec<P3>,
    /// Unit face normals at the points.
    pub normals: Vec<P3>,
}

impl SurfaceSamples {
    /// `count` samples drawn with `seed`.
    pub fn new(vertices: &[P3], triangles: &[[u32; 3]], count: usize, seed: u64) -> Self {
        let mut cumulative = Vec::with_capacity(triangles.len());
        let mut total = 0.0;
        let mut normals = Vec::with_capacity(triangles.len());
        for t in triangles {
            let [a, b, c] = t.map(|v| vertices[v as usize]);
            let n = cross(sub(b, a), sub(c, a));
            let len = norm(n);
            total += 0.5 * len;
            cumulative.push(total);
            normals.push(if len > 0.0 {
                n.map(|x| x / len)
            } else {
                [0.0, 0.0, 0.0]
            });
        }
        let mut rng = ChaCha8Rng::seed_from_u64(seed);
        let mut out = SurfaceSamples {
            points: Vec::with_capacity(count),
            normals: Vec::with_capacity(count),
        };
        if total <= 0.0 {
            return out;
        }
        for _ in 0..count {
            let r: f64 = rng.random::<f64>() * total;
            let f = cumulative
                .partition_point(|&c| c < r)
                .min(triangles.len() - 1);
            let (mut u, mut v): (f64, f64) = (rng.random(), rng.random());
            if u + v > 1.0 {
                (u, v) = (1.0 - u, 1.0 - v);
            }
            let [a, b, c] = triangles[f].map(|i| vertices[i as usize]);
            out.points
                .push([0, 1, 2].map(|k| a[k] + u * (b[k] - a[k]) + v * (c[k] - a[k])));
            out.normals.push(normals[f]);
        }
        out
    }

    fn tree(&self) -> Tree {
        Tree::new_from_slice(&self.points)
    }
}

/// Nearest-pair terms from `from` to `to`: mean squared distance, mean distance, mean (1 - |cos|).
fn directed(from: &SurfaceSamples, to: &SurfaceSamples, tree: &Tree) -> (f64, f64, f64) {
    let n = from.points.len().max(1) as f64;
    let (mut sq, mut d, mut nc) = (0.0, 0.0, 0.0);
    for (p, np) in from.points.iter().zip(&from.normals) {
        let hit = tree.nearest_one::<SquaredEuclidean>(p);
        sq += hit.distance;
        d += hit.distance.sqrt();
        nc += 1.0 - dot(*np, to.normals[hit.item as usize]).abs();
    }
    (sq / n, d / n, nc / n)
}

/// The symmetric sample terms: E_CD (sum of both directions' mean squared distances, x 100),
/// E_CD_cm (mean of both directions' mean distances, cm) and E_n (sum of both directions'
/// mean 1 - |cos|).
fn chamfer(a: &SurfaceSamples, b: &SurfaceSamples) -> (f64, f64, f64) {
    let (sq1, d1, n1) = directed(a, b, &b.tree());
    let (sq2, d2, n2) = directed(b, a, &a.tree());
    (100.0 * (sq1 + sq2), 100.0 * 0.5 * (d1 + d2), n1 + n2)
}

fn area_and_centroid(v: &[P3], tris: &[[u32; 3]]) -> (Vec<f64>, P3) {
    let mut areas = Vec::with_capacity(tris.len());
    let mut c = [0.0; 3];
    let mut total = 0.0;
    for t in tris {
        let [a, b, d] = t.map(|i| v[i as usize]);
        let area = 0.5 * norm(cross(sub(b, a), sub(d, a)));
        for k in 0..3 {
            c[k] += area * (a[k] + b[k] + d[k]) / 3.0;
        }
        total += area;
        areas.push(area);
    }
    (areas, c.map(|x| x / total.max(1e-300)))
}

/// Signed dihedral angle at each interior edge (negative where concave), in edge order of
/// `interior_edges`: (v0, v1, opposite in face A, opposite in face B).
fn dihedrals(v: &[P3], edges: &[[u32; 4]]) -> Vec<f64> {
    edges
        .iter()
        .map(|&[a, b, c, d]| {
            let (pa, pb, pc, pd) = (v[a as usize], v[b as usize], v[c as usize], v[d as usize]);
            let e = sub(pb, pa);
            let n1 = cross(e, sub(pc, pa));
            let n2 = cross(sub(pd, pa), e);
            let (l1, l2, le) = (norm(n1), norm(n2), norm(e));
            if l1 == 0.0 || l2 == 0.0 || le == 0.0 {
                return 0.0;
            }
            let (n1, n2) = (n1.map(|x| x / l1), n2.map(|x| x / l2));
            let sin = dot(cross(n1, n2), e.map(|x| x / le));
            sin.atan2(dot(n1, n2))
        })
        .collect()
}

/// Interior edges with their two opposite vertices: [a, b, c, d] where face (a, b, c) and
/// face (b, a, d) share the edge a-b.
pub fn interior_edges(triangles: &[[u32; 3]]) -> Vec<[u32; 4]> {
    let mut first: std::collections::BTreeMap<(u32, u32), [u32; 3]> = Default::default();
    let mut out = Vec::new();
    for t in triangles {
        for k in 0..3 {
            let (a, b, o) = (t[k], t[(k + 1) % 3], t[(k + 2) % 3]);
            let key = (a.min(b), a.max(b));
            match first.get(&key) {
                Some(&[fa, fb, fo]) => out.push([fa, fb, fo, o]),
                None => {
                    first.insert(key, [a, b, o]);
                }
            }
        }
    }
    out
}

/// Scores frames of one garment template against ground truth.
pub struct Scorer {
    triangles: Vec<[u32; 3]>,
    rest_areas: Vec<f64>,
    edges: Vec<[u32; 4]>,
    seed: u64,
    samples: usize,
}

/// A body surface for the collision terms.
pub struct BodySurface<'a> {
    /// Vertices, m.
    pub vertices: &'a [P3],
    /// Triangles, outward.
    pub triangles: &'a [[u32; 3]],
}

impl Scorer {
    /// For a template (rest positions and triangles); `seed` fixes the surface samples.
    pub fn new(rest: &[P3], triangles: &[[u32; 3]], seed: u64) -> Self {
        let (rest_areas, _) = area_and_centroid(rest, triangles);
        Self {
            triangles: triangles.to_vec(),
            rest_areas,
            edges: interior_edges(triangles),
            seed,
            samples: SAMPLES,
        }
    }

    /// Uses `count` surface samples instead of 50,000 (tests).
    pub fn with_samples(mut self, count: usize) -> Self {
        self.samples = count;
        self
    }

    fn strain(&self, areas: &[f64]) -> f64 {
        let n = areas.len().max(1) as f64;
        areas
            .iter()
            .zip(&self.rest_areas)
            .map(|(a, a0)| ((a - a0) / a0).powi(2) * a)
            .sum::<f64>()
            / n
    }

    /// The seed of frame `frame`'s surface samples.
    fn frame_seed(&self, frame: usize) -> u64 {
        self.seed ^ (frame as u64).wrapping_mul(0x9E37_79B9_7F4A_7C15)
    }

    /// E_c and E_c_vertex: garment surface samples and vertices inside the body, %.
    fn inside(
        &self,
        samples: &SurfaceSamples,
        vertices: &[P3],
        b: &BodySurface,
        seed: u64,
    ) -> (f64, f64) {
        let sb = SurfaceSamples::new(b.vertices, b.triangles, self.samples, seed ^ 0x5A5A_5A5A);
        let tb = sb.tree();
        let inside = |p: &P3| {
            let q = tb.nearest_one::<SquaredEuclidean>(p).item as usize;
            dot(sub(*p, sb.points[q]), sb.normals[q]) < 0.0
        };
        let frac = |pts: &[P3]| {
            100.0 * pts.iter().filter(|p| inside(p)).count() as f64 / pts.len().max(1) as f64
        };
        (frac(&samples.points), frac(vertices))
    }

    /// The collision terms alone, (E_c, E_c_vertex) in %, for a frame without ground truth
    /// (a prediction): the same samples [`Self::frame`] scores them with.
    pub fn collision(&self, pred: &[P3], body: &BodySurface, frame: usize) -> (f64, f64) {
        let seed = self.frame_seed(frame);
        let sp = SurfaceSamples::new(pred, &self.triangles, self.samples, seed);
        self.inside(&sp, pred, body, seed)
    }

    /// Scores one frame: `pred` against `gt` (same vertex order), `body` for E_c.
    pub fn frame(
        &self,
        pred: &[P3],
        gt: &[P3],
        body: Option<&BodySurface>,
        frame: usize,
    ) -> Scores {
        let n = pred.len().max(1) as f64;
        let e_v = 100.0
            * pred
                .iter()
                .zip(gt)
                .map(|(a, b)| norm(sub(*a, *b)))
                .sum::<f64>()
            / n;
        let seed = self.frame_seed(frame);
        let sp = SurfaceSamples::new(pred, &self.triangles, self.samples, seed);
        // The same stream for both meshes: identical meshes get identical samples (E_CD = 0).
        let sg = SurfaceSamples::new(gt, &self.triangles, self.samples, seed);
        let (e_cd, e_cd_cm, e_n) = chamfer(&sp, &sg);
        let (ap, cp) = area_and_centroid(pred, &self.triangles);
        let (ag, cg) = area_and_centroid(gt, &self.triangles);
        let (dp, dg) = (dihedrals(pred, &self.edges), dihedrals(gt, &self.edges));
        let e_b = if dp.is_empty() {
            0.0
        } else {
            (dp.iter()
                .zip(&dg)
                .map(|(a, b)| (a - b).powi(2))
                .sum::<f64>()
                / dp.len() as f64)
                .sqrt()
        };
        let (e_c, e_c_vertex) = match body {
            Some(b) => self.inside(&sp, pred, b, seed),
            None => (f64::NAN, f64::NAN),
        };
        Scores {
            E_v: e_v,
            E_CD: e_cd,
            E_CD_cm: e_cd_cm,
            E_n: e_n,
            E_c: e_c,
            E_c_vertex: e_c_vertex,
            E_b: e_b,
            E_s: 1e5 * (self.strain(&ap) - self.strain(&ag)).abs(),
            E_d: 100.0 * norm(sub(cp, cg)),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn jitter_is_zero_for_uniform_motion_and_the_second_difference_otherwise() {
        let line: Vec<Vec<P3>> = (0..5)
            .map(|k| vec![[0.1 * k as f64, 0.0, 0.0]; 2])
            .collect();
        assert!(jitter(&line) < 1e-12);
        // One vertex kicked 1 cm at frame 2 of 4: second differences 1, 2, 1 cm at frames 1-3.
        let mut kicked = line.clone();
        kicked[2][0][1] = 0.01;
        let expected = (1.0 + 2.0 + 1.0) / 6.0;
        assert!(
            (jitter(&kicked) - expected).abs() < 1e-9,
            "{}",
            jitter(&kicked)
        );
        assert_eq!(jitter(&line[..2]), 0.0);
    }

    /// A flat n x n grid patch of side 1 m in the x-z plane at height y.
    fn patch(n: usize, y: f64) -> (Vec<P3>, Vec<[u32; 3]>) {
        let mut v = Vec::new();
        for i in 0..n {
            for j in 0..n {
                v.push([i as f64 / (n - 1) as f64, y, j as f64 / (n - 1) as f64]);
            }
        }
        let mut t = Vec::new();
        for i in 0..n - 1 {
            for j in 0..n - 1 {
                let id = |a: usize, b: usize| (a * n + b) as u32;
                t.push([id(i, j), id(i, j + 1), id(i + 1, j)]);
                t.push([id(i + 1, j), id(i, j + 1), id(i + 1, j + 1)]);
            }
        }
        (v, t)
    }

    fn sphere(r: f64, c: P3) -> (Vec<P3>, Vec<[u32; 3]>) {
        // UV sphere, outward.
        let (nu, nv) = (48, 24);
        let mut v = vec![[c[0], c[1] + r, c[2]]];
        for i in 1..nv {
            let th = std::f64::consts::PI * i as f64 / nv as f64;
            for j in 0..nu {
                let ph = std::f64::consts::TAU * j as f64 / nu as f64;
                v.push([
                    c[0] + r * th.sin() * ph.cos(),
                    c[1] + r * th.cos(),
                    c[2] + r * th.sin() * ph.sin(),
                ]);
            }
        }
        v.push([c[0], c[1] - r, c[2]]);
        let ring = |i: usize, j: usize| (1 + (i - 1) * nu + j % nu) as u32;
        let mut t = Vec::new();
        for j in 0..nu {
            t.push([0, ring(1, j + 1), ring(1, j)]);
            t.push([(v.len() - 1) as u32, ring(nv - 1, j), ring(nv - 1, j + 1)]);
        }
        for i in 1..nv - 1 {
            for j in 0..nu {
                t.push([ring(i, j), ring(i, j + 1), ring(i + 1, j)]);
                t.push([ring(i + 1, j), ring(i, j + 1), ring(i + 1, j + 1)]);
            }
        }
        (v, t)
    }

    #[test]
    fn identical_meshes_score_zero() {
        let (v, t) = patch(11, 0.0);
        let s = Scorer::new(&v, &t, 1)
            .with_samples(5000)
            .frame(&v, &v, None, 0);
        assert_eq!(s.E_v, 0.0);
        assert!(
            s.E_CD == 0.0
                && s.E_CD_cm == 0.0
                && s.E_n < 1e-12
                && s.E_b == 0.0
                && s.E_s == 0.0
                && s.E_d == 0.0,
            "{s:?}"
        );
    }

    #[test]
    fn translation_gives_its_distance() {
        let (v, t) = patch(11, 0.0);
        let shifted: Vec<P3> = v.iter().map(|p| [p[0], p[1] + 0.02, p[2]]).collect();
        let s = Scorer::new(&v, &t, 1)
            .with_samples(5000)
            .frame(&shifted, &v, None, 0);
        assert!((s.E_v - 2.0).abs() < 1e-9, "E_v {} cm, expected 2", s.E_v);
        assert!((s.E_d - 2.0).abs() < 1e-9, "E_d {} cm, expected 2", s.E_d);
        // Along the normal every nearest pair is 2 cm apart (up to sample spacing): E_CD =
        // 100 * (0.02^2 + 0.02^2) = 0.08 (100 m^2), E_CD_cm = 2.
        assert!((s.E_CD - 0.08).abs() < 1e-9, "E_CD {}", s.E_CD);
        assert!((s.E_CD_cm - 2.0).abs() < 1e-9, "E_CD_cm {}", s.E_CD_cm);
        assert!(s.E_n < 1e-12 && s.E_b < 1e-12 && s.E_s < 1e-9);
    }

    #[test]
    fn flipped_and_tilted_patches_give_the_normal_term() {
        let (v, t) = patch(11, 0.0);
        // Orientation is ignored (|cos|): the patch mirrored in x lies in the same plane with
        // every normal reversed (cos = -1 exactly), and scores 0 where plain cos would give
        // 2 per direction.
        let scorer = Scorer::new(&v, &t, 3).with_samples(5000);
        let mirrored: Vec<P3> = v.iter().map(|p| [1.0 - p[0], p[1], p[2]]).collect();
        let s = scorer.frame(&mirrored, &v, None, 0);
        assert!(
            s.E_n < 1e-12,
            "E_n {} (4 if the sign of cos counted)",
            s.E_n
        );
        // Mean |1 - 2x| over x = i / 10: 6/11 m.
        assert!((s.E_v - 100.0 * 6.0 / 11.0).abs() < 1e-9, "E_v {}", s.E_v);
        // Tilted by 30 degrees about the x axis: each direction contributes 1 - cos 30.
        let a = 30f64.to_radians();
        let tilted: Vec<P3> = v
            .iter()
            .map(|p| [p[0], p[2] * a.sin(), p[2] * a.cos()])
            .collect();
        let s = scorer.frame(&tilted, &v, None, 0);
        let expected = 2.0 * (1.0 - a.cos());
        assert!(
            (s.E_n - expected).abs() < 1e-9,
            "E_n {} expected {expected}",
            s.E_n
        );
    }

    #[test]
    fn a_mesh_inside_a_sphere_collides_fully() {
        let (body_v, body_t) = sphere(0.5, [0.0, 0.0, 0.0]);
        let body = BodySurface {
            vertices: &body_v,
            triangles: &body_t,
        };
        let (inner, tri) = sphere(0.3, [0.0, 0.0, 0.0]);
        let scorer = Scorer::new(&inner, &tri, 5).with_samples(5000);
        let s = scorer.frame(&inner, &inner, Some(&body), 0);
        assert!(
            (s.E_c - 100.0).abs() < 1e-9 && (s.E_c_vertex - 100.0).abs() < 1e-9,
            "{s:?}"
        );
        let (outer, _) = sphere(0.6, [0.0, 0.0, 0.0]);
        let s = scorer.frame(&outer, &outer, Some(&body), 0);
        assert!(s.E_c == 0.0 && s.E_c_vertex == 0.0, "{s:?}");
    }

    /// Two different point sets (2 and 3 points, so a sum or a one-sided mean would show):
    /// A -> B has squared distances 0 and 0.01 and normal terms 0 and 0.2; B -> A has 0, 0.25
    /// and 0.01, and 0, 0 and 0.2.
    #[test]
    fn chamfer_of_different_shapes_matches_the_hand_values() {
        let a = SurfaceSamples {
            points: vec![[0.0, 0.0, 0.0], [1.0, 0.0, 0.0]],
            normals: vec![[0.0, 1.0, 0.0], [0.0, 1.0, 0.0]],
        };
        let b = SurfaceSamples {
            points: vec![[0.0, 0.0, 0.0], [0.5, 0.0, 0.0], [1.0, 0.1, 0.0]],
            normals: vec![[0.0, 1.0, 0.0], [0.0, -1.0, 0.0], [0.6, 0.8, 0.0]],
        };
        let (e_cd, e_cd_cm, e_n) = chamfer(&a, &b);
        let expected_cd = 100.0 * (0.01 / 2.0 + 0.26 / 3.0);
        assert!(
            (e_cd - expected_cd).abs() < 1e-9,
            "E_CD {e_cd} expected {expected_cd}"
        );
        assert!(
            (e_cd_cm - 12.5).abs() < 1e-9,
            "E_CD_cm {e_cd_cm} expected 12.5"
        );
        let expected_n = 0.2 / 2.0 + 0.2 / 3.0;
        assert!(
            (e_n - expected_n).abs() < 1e-12,
            "E_n {e_n} expected {expected_n}"
        );
        assert_eq!(chamfer(&b, &a), (e_cd, e_cd_cm, e_n), "symmetric");
    }

    /// A patch half inside a box (the box's face at x = 0.45 cuts the patch's columns
    /// x = 0, 0.1, ..., 1): 5 of 11 columns are inside, and the area-uniform samples inside
    /// are the share of area at x < 0.45.
    #[test]
    fn a_patch_half_inside_a_box_collides_by_its_share() {
        let (lo, hi) = ([-1.0, -0.5, -1.0], [0.45, 0.5, 2.0]);
        let box_v: Vec<P3> = (0..8)
            .map(|k| {
                [
                    if k & 1 == 1 { hi[0] } else { lo[0] },
                    if k & 2 == 2 { hi[1] } else { lo[1] },
                    if k & 4 == 4 { hi[2] } else { lo[2] },
                ]
            })
            .collect();
        let box_t = [
            [0, 4, 6],
            [0, 6, 2],
            [1, 3, 7],
            [1, 7, 5],
            [0, 1, 5],
            [0, 5, 4],
            [2, 6, 7],
            [2, 7, 3],
            [0, 2, 3],
            [0, 3, 1],
            [4, 5, 7],
            [4, 7, 6],
        ];
        let body = BodySurface {
            vertices: &box_v,
            triangles: &box_t,
        };
        let (v, t) = patch(11, 0.0);
        let s = Scorer::new(&v, &t, 7)
            .with_samples(20_000)
            .frame(&v, &v, Some(&body), 0);
        assert!(
            (s.E_c_vertex - 100.0 * 55.0 / 121.0).abs() < 1e-9,
            "E_c_vertex {}",
            s.E_c_vertex
        );
        // Binomial spread of 20,000 samples: 0.35 points.
        assert!((s.E_c - 45.0).abs() < 1.5, "E_c {}", s.E_c);
    }

    #[test]
    fn uniform_stretch_gives_the_strain_term() {
        let (v, t) = patch(11, 0.0);
        let k = 1.1;
        let stretched: Vec<P3> = v.iter().map(|p| [p[0] * k, p[1], p[2] * k]).collect();
        let scorer = Scorer::new(&v, &t, 1).with_samples(2000);
        let s = scorer.frame(&stretched, &v, None, 0);
        let a0 = 0.5 / 100.0; // each of the 200 triangles
        let expected = 1e5 * (k * k - 1.0).powi(2) * k * k * a0;
        assert!(
            (s.E_s / expected - 1.0).abs() < 1e-9,
            "E_s {} expected {expected}",
            s.E_s
        );
    }

    #[test]
    fn dihedral_sign_and_bending_term() {
        let (v, t) = patch(3, 0.0);
        // Fold the patch along x = 0.5 by lifting the far column: every interior edge on the
        // fold line bends.
        let folded: Vec<P3> = v
            .iter()
            .map(|p| {
                if p[0] > 0.75 {
                    [0.5 + 0.5 * 0.8, 0.5 * 0.6, p[2]]
                } else {
                    *p
                }
            })
            .collect();
        let s = Scorer::new(&v, &t, 1)
            .with_samples(1000)
            .frame(&folded, &v, None, 0);
        // The strip folds up along (0.8, 0.6): the two interior edges on x = 0.5 bend by
        // theta = atan2(0.6, 0.8), the other six not at all, so E_b = sqrt(2 theta^2 / 8).
        let theta = 0.6f64.atan2(0.8);
        assert!(
            (s.E_b - theta / 2.0).abs() < 1e-12,
            "E_b {} expected {}",
            s.E_b,
            theta / 2.0
        );
        let d = dihedrals(&folded, &interior_edges(&t));
        let bent: Vec<f64> = d.iter().copied().filter(|a| a.abs() > 1e-12).collect();
        assert!(
            d.len() == 8 && bent.len() == 2 && bent.iter().all(|a| (a + theta).abs() < 1e-12),
            "{d:?}"
        );
        let back = Scorer::new(&v, &t, 1)
            .with_samples(1000)
            .frame(&v, &folded, None, 0);
        assert!((back.E_b - s.E_b).abs() < 1e-12);
    }
}
