//! New UVs for a mesh that has none, laid out as a sewing pattern's panels are: charts never
//! cross the panels the caller names, each chart is turned (and mirrored where the panel is
//! seen from behind) to agree with a plane the caller gives per vertex, scaled to true size,
//! and packed unrotated by the pattern packer ([`crate::pattern::uv::pack`]).
//!
//! Why: the surrogate reads a garment through its geometry image, and it learned on library
//! designs whose panels lie upright in UV space at one common scale (front panels as seen from
//! the front, back panels mirrored, sleeves along the arm of the T-pose). An unwrapper's charts
//! are cut by normal cones and rotated freely to pack densely; measured on issue 57's round
//! trip, a prediction from such UVs is 0.18 cm (21%) further from the truth than from the
//! pattern's own (docs/GARMENTS.md).
//!
//! Charts are cut and flattened (from the mesh smoothed [`SMOOTHING_ROUNDS`] times) by `uvunwrap` (pure Rust, in the manner of xatlas: charts grown
//! within a normal cone, flattened by least-squares conformal maps), chosen over xatlas's C++
//! bindings so that nothing needs a C++ toolchain; the orientation and the layout are ours,
//! since no unwrapper takes a target orientation per chart.

use std::collections::BTreeMap;

use crate::error::{Error, Result};
use crate::mesh::Garment;
use crate::pattern::uv::pack;

/// The largest angle, degrees, between a triangle's normal and its chart's mean normal: wide,
/// so that a panel that wraps half way round a body (a shirt's front, from side to side) stays
/// one chart; the unwrapper still splits charts whose area distortion passes its bound.
pub const MAX_CHART_ANGLE_DEG: f32 = 88.0;

/// Rounds of averaging each vertex with its neighbours before charts are cut and flattened, so
/// that folds and wrinkles (whose triangles face every way) do not split a panel into specks:
/// measured on issue 57's round trip, 117 charts unsmoothed, 34 at 5 rounds, 32 at 20 (six of
/// them hold 93% of the triangles), 30 at 60, where the flattening starts to distort.
pub const SMOOTHING_ROUNDS: usize = 20;

/// How a mesh is cut into panels and how each panel is laid out.
#[derive(Debug, Clone, PartialEq)]
pub struct PanelGuide {
    /// Panel names; `triangle_panels` indexes them.
    pub names: Vec<String>,
    /// The panel of each triangle; charts never span two.
    pub triangle_panels: Vec<u32>,
    /// Per vertex, its point in the plane charts are laid out in (m): each chart is turned
    /// (mirrored where that fits better) and scaled to agree with it, never sheared.
    pub plane: Vec<[f64; 2]>,
}

fn unwrap_error(g: &Garment, problem: impl Into<String>) -> Error {
    Error::Unwrap {
        garment: g.name.clone(),
        problem: problem.into(),
    }
}

/// New UVs for the whole mesh, one page in [0, 1], per corner, cut and laid out by `guide`
/// (see the module's doc); the garment's panels become the guide's. Returns the chart count.
pub fn unwrap_uvs(g: &mut Garment, guide: &PanelGuide) -> Result<usize> {
    if guide.triangle_panels.len() != g.triangles.len() || guide.plane.len() != g.positions.len() {
        return Err(unwrap_error(
            g,
            format!(
                "the panel guide has {} triangles and {} points for {} triangles and {} vertices",
                guide.triangle_panels.len(),
                guide.plane.len(),
                g.triangles.len(),
                g.positions.len()
            ),
        ));
    }
    if let Some(p) = guide
        .triangle_panels
        .iter()
        .find(|&&p| p as usize >= guide.names.len())
    {
        return Err(unwrap_error(g, format!("panel {p} is not named")));
    }
    let indices: Vec<u32> = g.triangles.iter().flatten().copied().collect();
    let positions: Vec<[f32; 3]> = smoothed(&g.positions, &g.triangles, SMOOTHING_ROUNDS)
        .iter()
        .map(|p| p.map(|c| c as f32))
        .collect();
    let mesh = uvunwrap::MeshInput {
        face_materials: Some(&guide.triangle_panels),
        ..uvunwrap::MeshInput::new(&positions, &indices)
    };
    let options = uvunwrap::Options {
        max_chart_angle: MAX_CHART_ANGLE_DEG,
        ..Default::default()
    };
    let atlas =
        uvunwrap::generate(&[mesh], &options).map_err(|e| unwrap_error(g, e.to_string()))?;
    let out = atlas
        .meshes
        .first()
        .ok_or_else(|| unwrap_error(g, "the unwrapper returned no mesh"))?;
    if out.indices.len() != indices.len() {
        return Err(unwrap_error(g, "the unwrapper dropped triangles"));
    }
    // Output vertices by chart (seam vertices are duplicated, so each has one chart; corners of
    // degenerate triangles have none and are laid out as one more island).
    let mut charts: BTreeMap<Option<u32>, Vec<usize>> = BTreeMap::new();
    for (i, v) in out.vertices.iter().enumerate() {
        charts.entry(v.chart).or_default().push(i);
    }
    let islands: Vec<Vec<[f64; 2]>> = charts
        .values()
        .map(|members| {
            let uv: Vec<[f64; 2]> = members
                .iter()
                .map(|&i| out.vertices[i].uv.map(f64::from))
                .collect();
            let plane: Vec<[f64; 2]> = members
                .iter()
                .map(|&i| guide.plane[out.vertices[i].xref as usize])
                .collect();
            laid_like(&uv, &plane)
        })
        .collect();
    let packed = pack(&islands);
    let mut uvs = vec![[0.0; 2]; out.vertices.len()];
    for (members, island) in charts.values().zip(packed) {
        for (&i, p) in members.iter().zip(island) {
            uvs[i] = p;
        }
    }
    g.uvs = uvs;
    g.uv_triangles = out
        .indices
        .chunks_exact(3)
        .map(|c| [c[0], c[1], c[2]])
        .collect();
    g.panels = guide.names.clone();
    g.triangle_panels = guide.triangle_panels.clone();
    Ok(charts.keys().filter(|c| c.is_some()).count())
}

/// Taubin's smoothing (a shrinking step towards the neighbours' mean, then an inflating one)
/// `rounds` times: folds and wrinkles go, the garment's size and overall shape stay.
fn smoothed(positions: &[[f64; 3]], triangles: &[[u32; 3]], rounds: usize) -> Vec<[f64; 3]> {
    const SHRINK: f64 = 0.5;
    const INFLATE: f64 = -0.53;
    let neighbours = crate::vertex_neighbours(positions.len(), triangles);
    let mut out = positions.to_vec();
    for factor in [SHRINK, INFLATE].into_iter().cycle().take(2 * rounds) {
        let previous = out.clone();
        for (p, ring) in out.iter_mut().zip(&neighbours) {
            if ring.is_empty() {
                continue;
            }
            let n = ring.len() as f64;
            for k in 0..3 {
                let mean = ring.iter().map(|&j| previous[j as usize][k]).sum::<f64>() / n;
                p[k] += factor * (mean - p[k]);
            }
        }
    }
    out
}

/// `uv` turned, mirrored where that fits `plane` better, and scaled: the similarity that best
/// maps the points onto `plane` in the least-squares sense, without its translation.
fn laid_like(uv: &[[f64; 2]], plane: &[[f64; 2]]) -> Vec<[f64; 2]> {
    let mean = |pts: &[[f64; 2]]| {
        let n = pts.len().max(1) as f64;
        pts.iter()
            .fold([0.0; 2], |s, p| [s[0] + p[0] / n, s[1] + p[1] / n])
    };
    let (cu, cq) = (mean(uv), mean(plane));
    let centred: Vec<[f64; 2]> = uv.iter().map(|p| [p[0] - cu[0], p[1] - cu[1]]).collect();
    // Cross-covariance M = sum q p^T of the centred points.
    let mut m = [[0.0; 2]; 2];
    for (p, q) in centred.iter().zip(plane) {
        let q = [q[0] - cq[0], q[1] - cq[1]];
        for r in 0..2 {
            for c in 0..2 {
                m[r][c] += q[r] * p[c];
            }
        }
    }
    // A mirror (u -> -u) where the best orthogonal map has determinant -1.
    let mirror = m[0][0] * m[1][1] - m[0][1] * m[1][0] < 0.0;
    if mirror {
        m[0][0] = -m[0][0];
        m[1][0] = -m[1][0];
    }
    // The rotation R maximizing sum q . R p, and the scale that best fits after it.
    let angle = (m[1][0] - m[0][1]).atan2(m[0][0] + m[1][1]);
    let (s, c) = angle.sin_cos();
    let norm: f64 = centred.iter().map(|p| p[0] * p[0] + p[1] * p[1]).sum();
    let scale = if norm > 0.0 {
        (c * (m[0][0] + m[1][1]) + s * (m[1][0] - m[0][1])) / norm
    } else {
        1.0
    };
    let scale = if scale > 0.0 { scale } else { 1.0 };
    centred
        .iter()
        .map(|p| {
            let u = if mirror { -p[0] } else { p[0] };
            [scale * (c * u - s * p[1]), scale * (s * u + c * p[1])]
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::uv_overlap;

    /// The test tube (axis along y, radius 0.2 m) cut into a front (z > 0) and a back panel,
    /// laid out in the plane (x, y).
    fn tube_and_guide() -> (Garment, PanelGuide) {
        let mut g = crate::builtin::tube_for_tests();
        g.uvs.clear();
        g.uv_triangles.clear();
        let triangle_panels = g
            .triangles
            .iter()
            .map(|t| {
                let z: f64 = t.iter().map(|&v| g.positions[v as usize][2]).sum();
                u32::from(z < 0.0)
            })
            .collect();
        let plane = g.positions.iter().map(|p| [p[0], p[1]]).collect();
        let guide = PanelGuide {
            names: vec!["front".into(), "back".into()],
            triangle_panels,
            plane,
        };
        (g, guide)
    }

    #[test]
    fn overlapping_charts_are_measured_and_unwrapping_removes_them() {
        let mut g = crate::builtin::tube_for_tests();
        assert!(uv_overlap(&g) < 0.01);
        // A second layer of the same triangles on the same charts.
        let copy = g.clone();
        g.triangles.extend(copy.triangles);
        g.uv_triangles.extend(copy.uv_triangles);
        assert!(uv_overlap(&g) > 0.9, "{}", uv_overlap(&g));
        let (mut h, guide) = tube_and_guide();
        unwrap_uvs(&mut h, &guide).unwrap();
        assert_eq!(h.uv_triangles.len(), h.triangles.len());
        assert!(uv_overlap(&h) < 0.02, "{}", uv_overlap(&h));
        h.validate().unwrap();
    }

    /// Every chart keeps to one panel, and lies as the plane says: u grows with x and v with
    /// y on both panels, so the front's triangles keep their winding in UV space and the
    /// back's (seen from behind) are mirrored, as a sewing pattern's panels are.
    #[test]
    fn charts_keep_to_their_panels_and_lie_as_the_plane_says() {
        let (mut g, guide) = tube_and_guide();
        let charts = unwrap_uvs(&mut g, &guide).unwrap();
        assert!((2..=4).contains(&charts), "{charts} charts");
        assert_eq!(g.panels, ["front", "back"]);
        for (panel, expected_sign) in [(0, 1.0), (1, -1.0)] {
            let mut agree = 0.0;
            let triangles = g.triangles.iter().zip(&g.uv_triangles);
            for ((t, uvt), _) in triangles
                .zip(&g.triangle_panels)
                .filter(|&(_, &p)| p == panel)
            {
                let [a, b, c] = uvt.map(|i| g.uvs[i as usize]);
                let area = (b[0] - a[0]) * (c[1] - a[1]) - (c[0] - a[0]) * (b[1] - a[1]);
                assert!(area * expected_sign > 0.0, "panel {panel}: area {area}");
                // Along each edge, du has the sign of dx and dv of dy where they are clear.
                for k in 0..3 {
                    let (i, j) = (t[k] as usize, t[(k + 1) % 3] as usize);
                    let (p, q) = (g.positions[i], g.positions[j]);
                    let (u, w) = (g.uvs[uvt[k] as usize], g.uvs[uvt[(k + 1) % 3] as usize]);
                    agree +=
                        ((q[0] - p[0]) * (w[0] - u[0]) + (q[1] - p[1]) * (w[1] - u[1])).signum();
                }
            }
            assert!(agree > 0.0, "panel {panel}: edges disagree with the plane");
        }
    }

    #[test]
    fn a_guide_of_another_mesh_is_refused() {
        let (mut g, mut guide) = tube_and_guide();
        guide.plane.pop();
        let e = unwrap_uvs(&mut g, &guide).unwrap_err();
        assert!(e.to_string().contains("panel guide"), "{e}");
    }
}
