//! Intersection guidance, the paper's L_c, and the optional push-out of D-Garment's code.
//!
//! The loss of one frame is L_c = 1/2 sum_p max(0, band - d(p))^2 over the decoded garment
//! vertices p, with d the signed distance to that frame's posed body (negative inside, from
//! parry3d's closest point and pseudo-normal inside test through [`MeshSurface`]) and `band`
//! the engine's contact offset (the gap the ground truth keeps). Its gradient, -(band - d) n
//! with n the outward normal, is the penetration itself: a step of one moves every vertex in
//! the band onto the band's edge. Squared rather than the paper's plain distance so that the
//! weight is a number of such steps, not a speed in the maps' units (docs/SURROGATE.md).
//! Vertices outside by more than the band get no gradient, so guidance never moves them.

use serde::{Deserialize, Serialize};
use sim::Vec3;
use sim::obstacles::MeshSurface;

use crate::error::{Result, bad_value};

/// The engine's default contact offset, m: where guidance and the push-out put vertices.
pub const CONTACT_BAND_M: f64 = 0.003;

/// How strongly and from when the sampler is guided out of the body.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct Guidance {
    /// Weight: each guided Euler step of length ds moves a vertex in the band by
    /// min(weight ds, 1) of its depth below the band's edge. 0 turns guidance off.
    pub weight: f64,
    /// Fraction of the steps done before guidance starts (the paper: half).
    pub start: f64,
    /// Band above the body surface that guidance keeps clear, m.
    pub band_m: f64,
    /// Guidance passes on the finished sample (no network call): each moves the vertices in
    /// the band onto its edge as far as the texels carry them (0 for runs before the key).
    #[serde(default)]
    pub refine: usize,
}

impl Default for Guidance {
    fn default() -> Self {
        Self {
            weight: 5.0,
            start: 0.5,
            band_m: CONTACT_BAND_M,
            refine: 0,
        }
    }
}

impl Guidance {
    /// Checks the values, naming the first bad one.
    pub fn validate(&self) -> Result<()> {
        if !(self.weight.is_finite() && self.weight >= 0.0) {
            let expected = "a weight >= 0 is needed; 0 turns guidance off";
            return Err(bad_value("guidance weight", self.weight, expected));
        }
        if !(0.0..=1.0).contains(&self.start) {
            let expected = "a fraction of the steps in [0, 1]";
            return Err(bad_value("guidance start", self.start, expected));
        }
        if self.refine > 16 {
            return Err(bad_value("guidance refine", self.refine, "0 to 16 passes"));
        }
        if !(self.band_m.is_finite() && (0.0..=0.1).contains(&self.band_m)) {
            return Err(bad_value("guidance band", self.band_m, "0 to 0.1 m"));
        }
        Ok(())
    }

    /// Whether step `k` of `steps` is guided.
    pub fn guides(&self, k: usize, steps: usize) -> bool {
        self.weight > 0.0 && k as f64 >= self.start * steps as f64
    }
}

/// Where the body is relative to one point: signed distance (negative inside) and the outward
/// normal at the closest surface point.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Clearance {
    /// Signed distance, m.
    pub distance: f64,
    /// Outward unit normal.
    pub normal: [f64; 3],
}

/// The clearance of every point that is inside the body or within `reach` outside it; `None`
/// for points further out.
pub fn clearances(body: &MeshSurface, points: &[[f64; 3]], reach: f64) -> Vec<Option<Clearance>> {
    points.iter().map(|p| clearance(body, *p, reach)).collect()
}

/// Slack of the first, bounded query beyond `reach`, m: parry3d measures in f32, so a point
/// just beyond `reach` is still found and then judged in f64 as the unbounded query would be.
const BOUND_SLACK_M: f64 = 1e-3;

/// One point's clearance (see [`clearances`]). A point outside the body's bounding box by more
/// than `reach` is skipped without a query. Otherwise a query bounded near `reach` answers
/// every point within it (most of a garment is further out, where the bounded query stops
/// early); a point it does not find is further from the surface than that, and is inside
/// only where the winding number says so, which is the unbounded query's own test of the side:
/// only those points pay for the unbounded query. The answers are the unbounded query's.
fn clearance(body: &MeshSurface, p: [f64; 3], reach: f64) -> Option<Clearance> {
    let q = Vec3::from(p);
    if !body.near_bounds(q, reach) {
        return None;
    }
    let found = match body.query(q, reach.max(0.0) + BOUND_SLACK_M) {
        Some(found) => found,
        None if body.winding_number(q) > 0 => body.query(q, f64::INFINITY)?,
        None => return None,
    };
    (found.distance < reach).then(|| Clearance {
        distance: found.distance,
        normal: found.normal.into(),
    })
}

/// A point that moved less than this since a [`ClearanceCache`] asked keeps the cached answer,
/// m: far below the band and any metric's resolution, above the sampler's f32 rounding
/// (untouched texels come back from an Euler step a few nm away).
pub const REUSE_WITHIN_M: f64 = 1e-6;

/// The clearances of one frame's points from the last query of the same body, so a later
/// query asks again only for the points that moved: a guidance refinement pass moves only the
/// vertices in the band and their texel neighbours.
#[derive(Debug, Clone, Default)]
pub struct ClearanceCache {
    points: Vec<[f64; 3]>,
    clearances: Vec<Option<Clearance>>,
    reach: f64,
}

impl ClearanceCache {
    /// The clearances of `points` (as [`clearances`] gives them, up to [`REUSE_WITHIN_M`]).
    pub fn clearances(
        &mut self,
        body: &MeshSurface,
        points: &[[f64; 3]],
        reach: f64,
    ) -> &[Option<Clearance>] {
        if self.points.len() != points.len() || self.reach != reach {
            self.points = points.to_vec();
            self.clearances = clearances(body, points, reach);
            self.reach = reach;
            return &self.clearances;
        }
        let within = REUSE_WITHIN_M * REUSE_WITHIN_M;
        for ((known, answer), p) in self.points.iter_mut().zip(&mut self.clearances).zip(points) {
            let moved: f64 = (0..3).map(|c| (p[c] - known[c]).powi(2)).sum();
            if moved >= within {
                *known = *p;
                *answer = clearance(body, *p, reach);
            }
        }
        &self.clearances
    }
}

/// The gradient of L_c with respect to every point, from their clearances.
pub fn penalty_gradient(clearance: &[Option<Clearance>], band: f64) -> Vec<[f64; 3]> {
    clearance
        .iter()
        .map(|c| match c {
            Some(c) if c.distance < band => {
                let depth = band - c.distance;
                c.normal.map(|n| -depth * n)
            }
            _ => [0.0; 3],
        })
        .collect()
}

/// Moves every point inside the body out along its normal to `band` above the surface
/// (D-Garment's post-process); returns how many moved.
pub fn push_out(points: &mut [[f64; 3]], clearance: &[Option<Clearance>], band: f64) -> usize {
    let mut moved = 0;
    for (p, c) in points.iter_mut().zip(clearance) {
        if let Some(c) = c
            && c.distance < 0.0
        {
            let step = band - c.distance;
            for (x, n) in p.iter_mut().zip(c.normal) {
                *x += step * n;
            }
            moved += 1;
        }
    }
    moved
}

/// Vertices inside the body and the deepest penetration, m (0 when none is inside).
pub fn penetration(clearance: &[Option<Clearance>]) -> (usize, f64) {
    clearance
        .iter()
        .flatten()
        .filter(|c| c.distance < 0.0)
        .fold((0, 0.0f64), |(n, deepest), c| {
            (n + 1, deepest.max(-c.distance))
        })
}

#[cfg(test)]
pub(crate) mod tests {
    use super::*;

    /// A closed, outward-oriented UV sphere of `radius` at `centre`.
    pub(crate) fn sphere(radius: f64, centre: [f64; 3]) -> (Vec<Vec3>, Vec<[u32; 3]>) {
        let (rings, segments) = (24u32, 48u32);
        let mut vertices = vec![Vec3::new(centre[0], centre[1] + radius, centre[2])];
        for i in 1..rings {
            let theta = std::f64::consts::PI * i as f64 / rings as f64;
            for j in 0..segments {
                let phi = std::f64::consts::TAU * j as f64 / segments as f64;
                vertices.push(Vec3::new(
                    centre[0] + radius * theta.sin() * phi.cos(),
                    centre[1] + radius * theta.cos(),
                    centre[2] - radius * theta.sin() * phi.sin(),
                ));
            }
        }
        vertices.push(Vec3::new(centre[0], centre[1] - radius, centre[2]));
        let bottom = vertices.len() as u32 - 1;
        let ring = |i: u32, j: u32| 1 + (i - 1) * segments + j % segments;
        let mut faces = Vec::new();
        for j in 0..segments {
            faces.push([0, ring(1, j), ring(1, j + 1)]);
            faces.push([bottom, ring(rings - 1, j + 1), ring(rings - 1, j)]);
        }
        for i in 1..rings - 1 {
            for j in 0..segments {
                let (a, b, c, d) = (
                    ring(i, j),
                    ring(i, j + 1),
                    ring(i + 1, j),
                    ring(i + 1, j + 1),
                );
                faces.push([a, c, b]);
                faces.push([b, c, d]);
            }
        }
        (vertices, faces)
    }

    #[test]
    fn a_gradient_step_of_one_puts_points_in_the_band_on_its_edge_and_leaves_the_rest() {
        let (v, f) = sphere(0.2, [0.0, 1.0, 0.0]);
        let body = MeshSurface::new("sphere", &v, &f).unwrap();
        let band = 0.003;
        // Along +x from the centre: deep inside, just inside, in the band, outside the band.
        let radii = [0.05, 0.195, 0.2015, 0.21, 0.5];
        let points: Vec<[f64; 3]> = radii.iter().map(|r| [*r, 1.0, 0.0]).collect();
        let c = clearances(&body, &points, band);
        assert!(c[0].is_some_and(|c| c.distance < -0.1), "{:?}", c[0]);
        assert!(c[3].is_none() && c[4].is_none(), "{c:?}");
        assert_eq!(penetration(&c).0, 2);
        let g = penalty_gradient(&c, band);
        let stepped: Vec<[f64; 3]> = points
            .iter()
            .zip(&g)
            .map(|(p, g)| [p[0] - g[0], p[1] - g[1], p[2] - g[2]])
            .collect();
        // Every point that was in the band ends on the band's edge (parry3d works in f32).
        let after = clearances(&body, &stepped, 0.01);
        for (k, c) in after.iter().enumerate().take(3) {
            let d = c.expect("near the body").distance;
            assert!((d - band).abs() < 1e-4, "point {k}: {d} m from the body");
        }
        assert_eq!(&stepped[3..], &points[3..]);
        let after = clearances(&body, &stepped, band);
        assert_eq!(penetration(&after).0, 0);
    }

    /// The bounded-first query answers as the unbounded one does, deep inside and far out
    /// included, and the cache re-asks only for the points that moved.
    #[test]
    fn the_bounded_first_query_and_the_cache_answer_as_the_unbounded_query() {
        let (v, f) = sphere(0.2, [0.0, 1.0, 0.0]);
        let body = MeshSurface::new("sphere", &v, &f).unwrap();
        let band = 0.003;
        let mut points = Vec::new();
        for k in 0..400 {
            let r = 0.002 + 0.25 * (k as f64 / 400.0);
            let (a, b) = (k as f64 * 0.731, k as f64 * 0.377);
            points.push([
                r * a.cos() * b.sin(),
                1.0 + r * a.sin() * b.sin(),
                r * b.cos(),
            ]);
        }
        let unbounded: Vec<Option<Clearance>> = points
            .iter()
            .map(|p| {
                body.query(Vec3::from(*p), f64::INFINITY)
                    .filter(|s| s.distance < band)
                    .map(|s| Clearance {
                        distance: s.distance,
                        normal: s.normal.into(),
                    })
            })
            .collect();
        assert!(unbounded.iter().flatten().any(|c| c.distance < -0.1));
        assert!(unbounded.iter().any(|c| c.is_none()));
        assert_eq!(clearances(&body, &points, band), unbounded);
        let mut cache = ClearanceCache::default();
        assert_eq!(cache.clearances(&body, &points, band), &unbounded[..]);
        // Move one point out of the body and one by less than the reuse distance.
        let mut moved = points.clone();
        moved[0] = [0.0, 1.5, 0.0];
        moved[1][0] += REUSE_WITHIN_M / 10.0;
        let again = cache.clearances(&body, &moved, band).to_vec();
        assert_eq!(again[0], None);
        assert_eq!(again[1], unbounded[1]);
        assert_eq!(&again[2..], &unbounded[2..]);
        assert_eq!(again[0], clearances(&body, &moved[..1], band)[0]);
    }

    #[test]
    fn push_out_moves_only_the_points_inside() {
        let (v, f) = sphere(0.2, [0.0; 3]);
        let body = MeshSurface::new("sphere", &v, &f).unwrap();
        let mut points = vec![[0.0, 0.1, 0.0], [0.0, 0.2015, 0.0], [0.0, 0.4, 0.0]];
        let before = points.clone();
        let c = clearances(&body, &points, 0.003);
        assert_eq!(push_out(&mut points, &c, 0.003), 1);
        let d = clearances(&body, &points[..1], 0.01)[0].unwrap().distance;
        assert!(
            (d - 0.003).abs() < 1e-4,
            "{:?} is {d} m from the body",
            points[0]
        );
        assert_eq!(&points[1..], &before[1..]);
    }

    #[test]
    fn bad_settings_are_named() {
        let bad = Guidance {
            weight: -1.0,
            ..Guidance::default()
        };
        assert!(
            bad.validate()
                .unwrap_err()
                .to_string()
                .contains("weight = -1")
        );
        let late = Guidance {
            start: 1.5,
            ..Guidance::default()
        };
        assert!(
            late.validate()
                .unwrap_err()
                .to_string()
                .contains("start = 1.5")
        );
        let g = Guidance::default();
        assert!(!g.guides(9, 20) && g.guides(10, 20));
        let off = Guidance { weight: 0.0, ..g };
        assert!(!off.guides(19, 20));
    }
}
