//! What each element must be: counts within limits, finite positions, indices in range, UVs
//! present and finite (those outside [0, 1] are repaired by [`normalize_uvs`]), and a
//! plausible scale in metres.

use super::{
    Finding, MAX_EXTENT_M, MAX_TEMPLATE_VERTICES, MAX_VERTEX_TRIANGLES, MIN_EXTENT_M, add,
};
use crate::mesh::Garment;

/// Appends the element findings; `vertex` names a vertex in an example.
pub(super) fn element_findings(
    g: &Garment,
    vertex: &dyn Fn(usize) -> String,
    findings: &mut Vec<Finding>,
) {
    let n = g.positions.len();
    if n > MAX_TEMPLATE_VERTICES {
        add(
            findings,
            "too many vertices",
            vec![format!("{n} vertices, at most {MAX_TEMPLATE_VERTICES}")],
            None,
        );
    }
    let mut triangles_of = vec![0usize; n];
    for v in g.triangles.iter().flatten().filter(|&&v| (v as usize) < n) {
        triangles_of[*v as usize] += 1;
    }
    add(
        findings,
        "vertices in too many triangles",
        (0..n)
            .filter(|&i| triangles_of[i] > MAX_VERTEX_TRIANGLES)
            .map(|i| {
                format!(
                    "{} in {} triangles, at most {MAX_VERTEX_TRIANGLES} (a fan of a large polygon)",
                    vertex(i),
                    triangles_of[i]
                )
            })
            .collect(),
        None,
    );
    add(
        findings,
        "non-finite positions",
        (0..n)
            .filter(|&i| !g.positions[i].iter().all(|c| c.is_finite()))
            .map(vertex)
            .collect(),
        None,
    );
    add(
        findings,
        "indices out of range",
        (0..g.triangles.len())
            .filter(|&t| g.triangles[t].iter().any(|&v| v as usize >= n))
            .map(|t| format!("triangle {t}"))
            .collect(),
        None,
    );
    let uv_ok = g.uv_triangles.len() == g.triangles.len()
        && g.uv_triangles
            .iter()
            .all(|t| t.iter().all(|&i| (i as usize) < g.uvs.len()));
    if !uv_ok {
        add(
            findings,
            "missing UVs",
            vec![format!(
                "{} UV triangles for {} triangles",
                g.uv_triangles.len(),
                g.triangles.len()
            )],
            None,
        );
    } else {
        add(
            findings,
            "non-finite UVs",
            (0..g.uvs.len())
                .filter(|&i| !g.uvs[i].iter().all(|c| c.is_finite()))
                .map(|i| format!("UV {i}"))
                .collect(),
            None,
        );
        add(
            findings,
            "UVs outside [0, 1]",
            (0..g.uvs.len())
                .filter(|&i| {
                    g.uvs[i]
                        .iter()
                        .any(|c| c.is_finite() && !(-1e-9..=1.0 + 1e-9).contains(c))
                })
                .map(|i| format!("UV {i} {:?}", g.uvs[i]))
                .collect(),
            Some("moved and scaled uniformly into [0, 1]"),
        );
    }
}

/// Appends a finding when the extent of the vertices in `used` is not a garment's in metres.
pub(super) fn scale_findings(g: &Garment, used: &[bool], findings: &mut Vec<Finding>) {
    // The scale of what the triangles use (a stray vertex is reported above).
    let mut lo = [f64::INFINITY; 3];
    let mut hi = [f64::NEG_INFINITY; 3];
    for (p, _) in g.positions.iter().zip(used).filter(|(_, u)| **u) {
        for k in 0..3 {
            lo[k] = lo[k].min(p[k]);
            hi[k] = hi[k].max(p[k]);
        }
    }
    let largest = (0..3).map(|k| hi[k] - lo[k]).fold(0.0, f64::max);
    if !(MIN_EXTENT_M..=MAX_EXTENT_M).contains(&largest) {
        add(
            findings,
            "implausible scale",
            vec![format!(
                "largest extent {largest:.3} (expected metres, {MIN_EXTENT_M}-{MAX_EXTENT_M}; \
                 a file in cm must be rescaled to metres: `garments check FILE --scale 0.01` \
                 tells whether that is enough)"
            )],
            None,
        );
    }
}

pub(super) fn normalize_uvs(uvs: &mut [[f64; 2]]) {
    let mut lo = [f64::INFINITY; 2];
    let mut hi = [f64::NEG_INFINITY; 2];
    for uv in uvs.iter() {
        for k in 0..2 {
            lo[k] = lo[k].min(uv[k]);
            hi[k] = hi[k].max(uv[k]);
        }
    }
    let span = (hi[0] - lo[0]).max(hi[1] - lo[1]).max(1e-12);
    for uv in uvs.iter_mut() {
        for k in 0..2 {
            uv[k] = ((uv[k] - lo[k]) / span).clamp(0.0, 1.0);
        }
    }
}
