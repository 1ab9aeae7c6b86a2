//! Built-in garments that need no files. `skirt` (also `default`) is a knee-length A-line
//! skirt fitted to the body it is made for: a tube of near-equilateral triangles (staggered
//! rings) whose radius at every height and angle clears the body's outline, non-decreasing
//! downward, plus a small flare. UVs unroll the tube (seam at the back).

use std::f64::consts::TAU;

use crate::error::{Error, Result};
use crate::mesh::Garment;

/// Built-in garment names.
pub const BUILTIN: [&str; 2] = ["skirt", "default"];

/// Built-in garment names as strings.
pub fn builtin_names() -> Vec<&'static str> {
    BUILTIN.to_vec()
}

/// Shape of the built-in skirt.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct SkirtParams {
    /// Length from the waist down, m. Default 0.5.
    pub length: f64,
    /// Clearance between body and cloth, m. Default 0.01.
    pub gap: f64,
    /// Flare: extra radius per metre of length. Default 0.15.
    pub flare: f64,
    /// Vertices around. Default 112.
    pub columns: usize,
    /// Rings from waist to hem. Default 45.
    pub rings: usize,
}

impl Default for SkirtParams {
    fn default() -> Self {
        Self {
            length: 0.5,
            gap: 0.01,
            flare: 0.15,
            columns: 112,
            rings: 45,
        }
    }
}

/// Angular bins of the body outline.
const BINS: usize = 72;
/// Body vertices further than this from the vertical axis (hands, arms) are ignored, m.
const TORSO_REACH: f64 = 0.3;

/// The skirt fitted to `body` (vertices of the body in its canonical pose, y up, facing +z).
/// `name` selects among [`BUILTIN`].
pub fn skirt(name: &str, body: &[[f64; 3]], params: &SkirtParams) -> Result<Garment> {
    if !BUILTIN.contains(&name) {
        return Err(Error::Unknown(name.to_string()));
    }
    if body.is_empty()
        || params.columns < 8
        || params.rings < 2
        || params.length.is_nan()
        || params.length <= 0.0
    {
        return Err(Error::BadParameter {
            parameter: "skirt",
            problem: "needs a body, at least 8 columns and 2 rings and a positive length".into(),
        });
    }
    let (lo, hi) = body
        .iter()
        .fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), p| {
            (a.min(p[1]), b.max(p[1]))
        });
    let height = hi - lo;
    let near_axis = |p: &[f64; 3], cz: f64| p[0].hypot(p[2] - cz) < TORSO_REACH;
    // Axis: centre of the torso's depth around hip height.
    let band: Vec<&[f64; 3]> = body
        .iter()
        .filter(|p| (p[1] - (lo + 0.55 * height)).abs() < 0.05 && p[0].abs() < TORSO_REACH)
        .collect();
    let cz = band.iter().map(|p| p[2]).fold(f64::INFINITY, f64::min) * 0.5
        + band.iter().map(|p| p[2]).fold(f64::NEG_INFINITY, f64::max) * 0.5;
    // Waist: the narrowest torso width between 58% and 68% of the height.
    let mut top = lo + 0.62 * height;
    let mut narrowest = f64::INFINITY;
    for k in 0..=20 {
        let y = lo + (0.58 + 0.005 * k as f64) * height;
        let width = body
            .iter()
            .filter(|p| (p[1] - y).abs() < 0.01 && near_axis(p, cz))
            .map(|p| p[0].abs())
            .fold(0.0, f64::max);
        if width > 0.0 && width < narrowest {
            narrowest = width;
            top = y;
        }
    }
    // Outline: for every ring, the largest radius of the body per angular bin from the waist
    // down to the ring (so the skirt never narrows downward).
    let dy = params.length / (params.rings - 1) as f64;
    let mut outline = vec![0.0f64; BINS];
    let mut radii = Vec::with_capacity(params.rings);
    let mut sorted: Vec<&[f64; 3]> = body
        .iter()
        .filter(|p| p[1] <= top + 0.02 && near_axis(p, cz))
        .collect();
    sorted.sort_by(|a, b| b[1].total_cmp(&a[1]));
    let mut next = 0;
    for r in 0..params.rings {
        let y = top - r as f64 * dy;
        while next < sorted.len() && sorted[next][1] >= y - 0.5 * dy {
            let p = sorted[next];
            let angle = p[0].atan2(p[2] - cz).rem_euclid(TAU);
            let bin = ((angle / TAU * BINS as f64) as usize).min(BINS - 1);
            outline[bin] = outline[bin].max(p[0].hypot(p[2] - cz));
            next += 1;
        }
        // Smooth: each bin takes the max of its neighbours (closes gaps between legs' bins).
        let smoothed: Vec<f64> = (0..BINS)
            .map(|b| {
                (0..5)
                    .map(|d| outline[(b + BINS + d - 2) % BINS])
                    .fold(0.0, f64::max)
            })
            .collect();
        radii.push(smoothed);
    }
    let radius = |ring: usize, theta: f64| {
        let bins = &radii[ring];
        let x = theta.rem_euclid(TAU) / TAU * BINS as f64 - 0.5;
        let i = x.floor();
        let f = x - i;
        let a = bins[(i as isize).rem_euclid(BINS as isize) as usize];
        let b = bins[((i as isize) + 1).rem_euclid(BINS as isize) as usize];
        a + (b - a) * f + params.gap + params.flare * ring as f64 * dy
    };
    let mut g = tube(
        name,
        radius,
        [0.0, top, cz],
        dy,
        params.rings,
        params.columns,
    );
    g.name = "skirt".into();
    g.panels = vec!["skirt".into()];
    g.vertex_labels
        .insert("waistband".into(), (0..params.columns as u32).collect());
    g.validate()?;
    Ok(g)
}

/// A tube of staggered rings (near-equilateral triangles) around the vertical axis through
/// `center`: ring r at height center.y - r dy with radius `radius(r, theta)`, theta = 0 at +z.
pub(crate) fn tube(
    name: &str,
    radius: impl Fn(usize, f64) -> f64,
    center: [f64; 3],
    dy: f64,
    rings: usize,
    columns: usize,
) -> Garment {
    let shift = |r: usize| if r % 2 == 1 { 0.5 } else { 0.0 };
    let mut positions = Vec::with_capacity(rings * columns);
    for r in 0..rings {
        for c in 0..columns {
            let theta = TAU * (c as f64 + shift(r)) / columns as f64;
            let rad = radius(r, theta);
            positions.push([
                center[0] + rad * theta.sin(),
                center[1] - r as f64 * dy,
                center[2] + rad * theta.cos(),
            ]);
        }
    }
    // UVs: columns + 1 per ring (the seam column repeats), u over the unrolled circumference,
    // v down the length, both scaled by the same factor.
    let span = columns as f64 + 0.5;
    let circumference: f64 = (0..columns)
        .map(|c| {
            let (a, b) = (positions[c], positions[(c + 1) % columns]);
            ((a[0] - b[0]).powi(2) + (a[2] - b[2]).powi(2)).sqrt()
        })
        .sum::<f64>()
        .max(dy * (rings - 1) as f64);
    let v_scale = 1.0 / circumference;
    let mut uvs = Vec::with_capacity(rings * (columns + 1));
    for r in 0..rings {
        for c in 0..=columns {
            uvs.push([
                (c as f64 + shift(r)) / span,
                (r as f64 * dy * v_scale).min(1.0),
            ]);
        }
    }
    let p = |r: usize, c: usize| (r * columns + c % columns) as u32;
    let t = |r: usize, c: usize| (r * (columns + 1) + c) as u32;
    let mut triangles = Vec::new();
    let mut uv_triangles = Vec::new();
    for r in 0..rings - 1 {
        for c in 0..columns {
            let (first, second) = if r % 2 == 0 {
                (
                    [(r, c), (r + 1, c), (r, c + 1)],
                    [(r, c + 1), (r + 1, c), (r + 1, c + 1)],
                )
            } else {
                (
                    [(r, c), (r + 1, c + 1), (r, c + 1)],
                    [(r, c), (r + 1, c), (r + 1, c + 1)],
                )
            };
            for tri in [first, second] {
                triangles.push(tri.map(|(r, c)| p(r, c)));
                uv_triangles.push(tri.map(|(r, c)| t(r, c)));
            }
        }
    }
    Garment::single_panel(name, positions, triangles, uvs, uv_triangles)
}

#[cfg(test)]
pub(crate) fn tube_for_tests() -> Garment {
    tube("tube", |_, _| 0.2, [0.0, 1.0, 0.0], 0.02, 6, 16)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn tube_is_valid_and_outward() {
        let g = tube_for_tests();
        g.validate().unwrap();
        assert_eq!(g.positions.len(), 96);
        // Every triangle's normal points away from the axis.
        for tri in &g.triangles {
            let [a, b, c] = tri.map(|v| g.positions[v as usize]);
            let n = crate::check::doubled_normal(a, b, c);
            let mid = [(a[0] + b[0] + c[0]) / 3.0, (a[2] + b[2] + c[2]) / 3.0];
            assert!(
                n[0] * mid[0] + n[2] * mid[1] > 0.0,
                "triangle {tri:?} faces inward"
            );
        }
    }

    #[test]
    fn skirt_clears_a_cylinder_body() {
        // A stand-in body: a vertical cylinder of radius 0.15 from y = 0 to 1.7.
        let body: Vec<[f64; 3]> = (0..170)
            .flat_map(|k| {
                (0..36).map(move |a| {
                    let t = a as f64 / 36.0 * TAU;
                    [0.15 * t.sin(), k as f64 * 0.01, 0.15 * t.cos()]
                })
            })
            .collect();
        let g = skirt("default", &body, &SkirtParams::default()).unwrap();
        assert_eq!(g.positions.len(), 112 * 45);
        for p in &g.positions {
            let r = p[0].hypot(p[2]);
            assert!(r > 0.15 + 0.009, "vertex at radius {r} is within the gap");
        }
        assert!(
            skirt("cape", &body, &SkirtParams::default())
                .unwrap_err()
                .to_string()
                .contains("unknown garment")
        );
    }
}
