//! The atlas of a template at one resolution: for every texel centre ((i + 0.5) / R,
//! (j + 0.5) / R) the UV triangle that holds it and its barycentrics, or, for a texel outside
//! every chart, the nearest triangle with extrapolated (unclamped) barycentrics; the mask of
//! the truly inside texels; and the chart (connected UV island) every texel belongs to, so
//! readback can ignore other charts' texels.
//!
//! Image layout everywhere: row `j` (v), column `i` (u), texel index `j * R + i`, v = 0 at row 0.

use rayon::prelude::*;

use crate::error::{Error, Result};

/// Resolutions the surrogate supports.
pub const RESOLUTIONS: [usize; 3] = [32, 64, 128];

/// A texel's triangle and barycentrics (inside texels: in [0, 1]; outside: extrapolated).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct TexelSample {
    /// The UV triangle (index into the template's triangles).
    pub triangle: u32,
    /// Barycentric weights of its three corners; they sum to 1.
    pub weights: [f64; 3],
}

/// Texel -> triangle map of one template at one resolution. Deterministic: built from the
/// UVs alone, ties broken by the lower triangle index.
#[derive(Debug, Clone, PartialEq)]
pub struct Atlas {
    resolution: usize,
    texels: Vec<TexelSample>,
    inside: Vec<bool>,
    texel_chart: Vec<u32>,
    corner_chart: Vec<u32>,
    charts: usize,
}

/// Twice the signed area of the UV triangle (a, b, c).
fn cross(a: [f64; 2], b: [f64; 2], c: [f64; 2]) -> f64 {
    (b[0] - a[0]) * (c[1] - a[1]) - (b[1] - a[1]) * (c[0] - a[0])
}

/// Barycentrics of `p` in (a, b, c), unclamped; `None` for a degenerate triangle.
fn barycentric(p: [f64; 2], [a, b, c]: [[f64; 2]; 3]) -> Option<[f64; 3]> {
    let area = cross(a, b, c);
    if area.abs() < 1e-18 {
        return None;
    }
    let wa = cross(p, b, c) / area;
    let wb = cross(a, p, c) / area;
    Some([wa, wb, 1.0 - wa - wb])
}

/// Squared distance from `p` to the segment (a, b).
fn segment_distance2(p: [f64; 2], a: [f64; 2], b: [f64; 2]) -> f64 {
    let (dx, dy) = (b[0] - a[0], b[1] - a[1]);
    let length2 = dx * dx + dy * dy;
    let t = if length2 > 0.0 {
        (((p[0] - a[0]) * dx + (p[1] - a[1]) * dy) / length2).clamp(0.0, 1.0)
    } else {
        0.0
    };
    let (ex, ey) = (a[0] + t * dx - p[0], a[1] + t * dy - p[1]);
    ex * ex + ey * ey
}

/// Squared distance from `p` to the triangle (0 inside).
fn triangle_distance2(p: [f64; 2], w: [f64; 3], t: [[f64; 2]; 3]) -> f64 {
    if w.iter().all(|&x| x >= 0.0) {
        return 0.0;
    }
    segment_distance2(p, t[0], t[1])
        .min(segment_distance2(p, t[1], t[2]))
        .min(segment_distance2(p, t[2], t[0]))
}

/// Connected components of the UV triangles (triangles sharing a UV corner), numbered in
/// order of their lowest triangle; returns each UV corner's chart and the chart count.
fn charts(uv_count: usize, uv_triangles: &[[u32; 3]]) -> (Vec<u32>, usize) {
    let mut parent: Vec<usize> = (0..uv_count).collect();
    fn root(parent: &mut [usize], mut i: usize) -> usize {
        while parent[i] != i {
            parent[i] = parent[parent[i]];
            i = parent[i];
        }
        i
    }
    for t in uv_triangles {
        let a = root(&mut parent, t[0] as usize);
        for &c in &t[1..] {
            let b = root(&mut parent, c as usize);
            if a != b {
                parent[b.max(a)] = b.min(a);
            }
        }
    }
    let mut number = vec![u32::MAX; uv_count];
    let mut chart = vec![u32::MAX; uv_count];
    let mut count = 0;
    for t in uv_triangles {
        for &c in t {
            let r = root(&mut parent, c as usize);
            if number[r] == u32::MAX {
                number[r] = count;
                count += 1;
            }
            chart[c as usize] = number[r];
        }
    }
    (chart, count as usize)
}

/// The texels inside the UV triangles (`corners`, per triangle) at `r` texels per side, with
/// their triangle and barycentrics: each triangle's bounding box scanned; the first triangle
/// (lowest index) holding a texel keeps it. The rest are None.
fn inside_texels(corners: &[[[f64; 2]; 3]], r: usize) -> (Vec<Option<TexelSample>>, Vec<bool>) {
    let mut inside = vec![false; r * r];
    let mut texels: Vec<Option<TexelSample>> = vec![None; r * r];
    for (t, tri) in corners.iter().enumerate() {
        let lo = |k: usize| tri.iter().map(|p| p[k]).fold(f64::INFINITY, f64::min);
        let hi = |k: usize| tri.iter().map(|p| p[k]).fold(f64::NEG_INFINITY, f64::max);
        let first = |x: f64| ((x * r as f64 - 0.5).ceil().max(0.0)) as usize;
        let last = |x: f64| ((x * r as f64 - 0.5).floor().min(r as f64 - 1.0)).max(-1.0);
        let (i0, i1, j0, j1) = (first(lo(0)), last(hi(0)), first(lo(1)), last(hi(1)));
        if i1 < 0.0 || j1 < 0.0 {
            continue;
        }
        for j in j0..=j1 as usize {
            for i in i0..=i1 as usize {
                let k = j * r + i;
                if texels[k].is_some() {
                    continue;
                }
                let p = [(i as f64 + 0.5) / r as f64, (j as f64 + 0.5) / r as f64];
                if let Some(w) = barycentric(p, *tri)
                    && w.iter().all(|&x| x >= -1e-12)
                {
                    texels[k] = Some(TexelSample {
                        triangle: t as u32,
                        weights: w,
                    });
                    inside[k] = true;
                }
            }
        }
    }
    (texels, inside)
}

/// The texels left outside every triangle, each with its nearest triangle and the
/// barycentrics extrapolated to it.
fn nearest_triangles(
    corners: &[[[f64; 2]; 3]],
    texels: &[Option<TexelSample>],
    r: usize,
) -> Vec<(usize, TexelSample)> {
    (0..r * r)
        .into_par_iter()
        .filter(|&k| texels[k].is_none())
        .filter_map(|k| {
            let p = [
                ((k % r) as f64 + 0.5) / r as f64,
                ((k / r) as f64 + 0.5) / r as f64,
            ];
            let mut best: Option<(f64, TexelSample)> = None;
            for (t, tri) in corners.iter().enumerate() {
                let Some(w) = barycentric(p, *tri) else {
                    continue;
                };
                let d = triangle_distance2(p, w, *tri);
                if best.is_none_or(|(b, _)| d < b) {
                    let sample = TexelSample {
                        triangle: t as u32,
                        weights: w,
                    };
                    best = Some((d, sample));
                }
            }
            best.map(|(_, s)| (k, s))
        })
        .collect()
}

impl Atlas {
    /// Builds the atlas of a template's UV layout (`uvs` in [0, 1]^2, one UV triangle per
    /// mesh triangle) at `resolution` texels per side.
    pub fn new(uvs: &[[f64; 2]], uv_triangles: &[[u32; 3]], resolution: usize) -> Result<Self> {
        if !RESOLUTIONS.contains(&resolution) {
            return Err(Error::Resolution { resolution });
        }
        if uv_triangles.is_empty() {
            return Err(Error::NoUvs);
        }
        if let Some(t) = uv_triangles
            .iter()
            .position(|t| t.iter().any(|&c| c as usize >= uvs.len()))
        {
            return Err(Error::BadUvTriangle {
                triangle: t,
                uvs: uvs.len(),
            });
        }
        if let Some(c) = uvs.iter().position(|p| !p.iter().all(|x| x.is_finite())) {
            return Err(Error::NonFiniteUv { corner: c });
        }
        let (corner_chart, chart_count) = charts(uvs.len(), uv_triangles);
        let corners: Vec<[[f64; 2]; 3]> = uv_triangles
            .iter()
            .map(|t| t.map(|c| uvs[c as usize]))
            .collect();
        let r = resolution;
        let (mut texels, inside) = inside_texels(&corners, r);
        for (k, sample) in nearest_triangles(&corners, &texels, r) {
            texels[k] = Some(sample);
        }
        let texels: Vec<TexelSample> = texels
            .into_iter()
            .collect::<Option<_>>()
            .ok_or(Error::NoUvs)?;
        let texel_chart = texels
            .iter()
            .map(|s| corner_chart[uv_triangles[s.triangle as usize][0] as usize])
            .collect();
        Ok(Self {
            resolution,
            texels,
            inside,
            texel_chart,
            corner_chart,
            charts: chart_count,
        })
    }

    /// Texels per side.
    pub fn resolution(&self) -> usize {
        self.resolution
    }

    /// Every texel's triangle and barycentrics, row by row.
    pub fn texels(&self) -> &[TexelSample] {
        &self.texels
    }

    /// Whether each texel centre lies inside a UV triangle.
    pub fn inside(&self) -> &[bool] {
        &self.inside
    }

    /// The chart each texel reads from (its triangle's).
    pub fn texel_chart(&self) -> &[u32] {
        &self.texel_chart
    }

    /// The chart of each UV corner.
    pub fn corner_chart(&self) -> &[u32] {
        &self.corner_chart
    }

    /// Number of charts (UV islands).
    pub fn charts(&self) -> usize {
        self.charts
    }

    /// Inside texels over all texels.
    pub fn coverage(&self) -> f64 {
        self.inside.iter().filter(|&&x| x).count() as f64 / self.inside.len() as f64
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Two triangles making the square [0.25, 0.75]^2, and a second chart far away.
    fn square() -> (Vec<[f64; 2]>, Vec<[u32; 3]>) {
        let uvs = vec![
            [0.25, 0.25],
            [0.75, 0.25],
            [0.75, 0.75],
            [0.25, 0.75],
            [0.85, 0.85],
            [0.95, 0.85],
            [0.95, 0.95],
        ];
        (uvs, vec![[0, 1, 2], [0, 2, 3], [4, 5, 6]])
    }

    #[test]
    fn texels_inside_hold_their_triangle_and_outside_ones_extrapolate() {
        let (uvs, tris) = square();
        let atlas = Atlas::new(&uvs, &tris, 32).unwrap();
        assert_eq!(atlas.charts(), 2);
        // Texel centres at (i + 0.5) / 32 within [0.25, 0.75]: i = 8..=23 (16 per side).
        let inside_square = (8..24)
            .flat_map(|j| (8..24).map(move |i| j * 32 + i))
            .all(|k| atlas.inside()[k]);
        assert!(inside_square);
        for (k, s) in atlas.texels().iter().enumerate() {
            let sum: f64 = s.weights.iter().sum();
            assert!((sum - 1.0).abs() < 1e-12, "texel {k}: weights sum to {sum}");
            if !atlas.inside()[k] {
                assert!(
                    s.weights.iter().any(|&w| w < 0.0),
                    "texel {k} outside, {s:?}"
                );
            }
        }
        // The corner texel (0, 0) is nearest the square, chart 0.
        assert_eq!(atlas.texel_chart()[0], 0);
        // The top-right corner texel is nearest the small triangle, chart 1.
        assert_eq!(atlas.texel_chart()[32 * 32 - 1], 1);
        let covered = atlas.coverage();
        assert!(
            (covered - (256.0 + 6.0) / 1024.0).abs() < 4.0 / 1024.0,
            "{covered}"
        );
    }

    #[test]
    fn bad_layouts_are_refused() {
        let (uvs, tris) = square();
        assert!(matches!(
            Atlas::new(&uvs, &tris, 48),
            Err(Error::Resolution { resolution: 48 })
        ));
        assert!(matches!(Atlas::new(&uvs, &[], 64), Err(Error::NoUvs)));
        assert!(matches!(
            Atlas::new(&uvs, &[[0, 1, 9]], 64),
            Err(Error::BadUvTriangle { triangle: 0, .. })
        ));
    }
}
