//! A user's own garment made a template (`garments import`): a mesh (a scan, an artist's
//! garment, a frame of a capture) as worn by a body of known shape at one frame of a known
//! motion becomes a template on the default body in its canonical A-pose, which `predict`
//! takes like a library design's.
//!
//! Stages, in order: the mesh cleaned (coincident vertices welded, then the documented repairs
//! of [`garments::repair`], which refuse non-manifold edges and the like by name); made fine
//! enough for the engine (split into four until its median edge is at most twice the
//! library's); given its rest shape, its own edges shrunk by [`REST_SHRINK`]; carried back
//! from the worn pose and shape to the canonical ones by the engine, the body blended over
//! [`UNWIND_FRAMES`] frames as a simulation's blend-in blends it forward
//! ([`sim::unwind::unwind`]); settled there with the gates of sewing
//! ([`sim::sewing::settle_on_body`]); given UVs where it has none or its charts overlap, cut
//! and laid out as a pattern's panels ([`crate::geometry::panel_guide`],
//! [`garments::unwrap_uvs`]).

use garments::Garment;
use motions::{BlendIn, BodyModel, FramePose, Motion, ShapedBody, canonical_a_pose};
use serde::Serialize;
use sim::sewing::{SewingOptions, SewingReport, settle_on_body};

use crate::error::{Error, Result};
use crate::geometry::panel_guide;

/// Frames the body takes from the worn pose and shape back to the canonical ones (a second, as
/// `simulate`'s default blend-in).
pub const UNWIND_FRAMES: usize = 30;

/// The body's vertices from `frame` with `shaped`'s betas back to the canonical A-pose with
/// none, over [`UNWIND_FRAMES`] frames (smoothstep, the root kept where `frame` has it).
fn unwinding_bodies(
    model: &BodyModel,
    shaped: &ShapedBody,
    frame: &FramePose,
) -> Result<Vec<Vec<[f64; 3]>>> {
    let blend = BlendIn {
        blend_frames: UNWIND_FRAMES,
        settle_frames: 0,
    };
    let forward =
        Motion::new("unwind", 30.0, vec![*frame])?.with_blend_in(&canonical_a_pose(), blend);
    let last = forward.frames.len() - 1;
    forward
        .frames
        .iter()
        .enumerate()
        .rev()
        .map(|(k, pose)| {
            let u = k as f64 / last as f64;
            let share = u * u * (3.0 - 2.0 * u);
            let betas: Vec<f64> = shaped.betas.iter().map(|b| b * share).collect();
            Ok(model.pose(&model.shape(&betas)?, pose)?.vertices)
        })
        .collect()
}

/// The rest shape's size against the worn mesh. The rest shape is the worn mesh's own geometry
/// (the engine's rest state is its edges' lengths and its triangles' areas; bending rests flat),
/// which a pose does not change: on issue 57's round trip the worn frame's edges are within
/// 0.2-0.5% of the template's. Unposing it by inverse skinning first, as before, stretched and
/// squeezed it where skinning bends the body. It is shrunk because the worn mesh's stretch under
/// its weight is settled a second time on the canonical body. Chosen on the round trip of
/// `shirt_mean` and `dress_pencil` (the template's E_CD_cm to the original at 1, 0.99, 0.985,
/// 0.98, 0.97, 0.96: 0.95, 0.90, 0.87, 0.86, 0.87, 0.89 and 1.37, 0.89, 0.85, 0.91, 0.81, 0.81;
/// docs/GARMENTS.md).
pub const REST_SHRINK: f64 = 0.97;

/// `points` scaled by `factor` about their centroid.
fn scaled_about_centroid(points: &mut [[f64; 3]], factor: f64) {
    let n = points.len().max(1) as f64;
    let centroid = points
        .iter()
        .fold([0.0; 3], |s, p| [0, 1, 2].map(|k| s[k] + p[k] / n));
    for p in points {
        *p = [0, 1, 2].map(|k| centroid[k] + factor * (p[k] - centroid[k]));
    }
}

/// How a mesh is imported.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ImportOptions {
    /// Factor the file's positions are multiplied by (0.01 for a file in cm).
    pub scale: f64,
    /// Vertices closer than this are welded into one, m.
    pub weld_m: f64,
    /// The largest fraction of the UV area covered twice that is kept; past it the mesh is
    /// unwrapped again.
    pub max_uv_overlap: f64,
    /// Median edge length the mesh is subdivided down to (at most twice this), m.
    pub edge_length_m: f64,
    /// The rest shape's size against the worn mesh ([`REST_SHRINK`]).
    pub rest_shrink: f64,
    /// The drape on the canonical body.
    pub sewing: SewingOptions,
}

impl Default for ImportOptions {
    fn default() -> Self {
        Self {
            scale: 1.0,
            weld_m: 1e-6,
            max_uv_overlap: 0.01,
            edge_length_m: garments::pattern::DEFAULT_EDGE_LENGTH_M,
            rest_shrink: REST_SHRINK,
            sewing: SewingOptions::default(),
        }
    }
}

/// What importing did, stage by stage.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct ImportReport {
    /// Vertices and triangles as read.
    pub vertices_read: usize,
    /// Triangles as read (polygons fanned).
    pub triangles_read: usize,
    /// Vertices welded into others.
    pub welded: usize,
    /// The repairs made, one line each.
    pub repairs: Vec<String>,
    /// Times every triangle was split into four.
    pub subdivisions: usize,
    /// Median edge length after subdividing, m.
    pub median_edge_m: f64,
    /// `kept`, or why new UVs were unwrapped (`none`, `overlapping`).
    pub uvs: String,
    /// Fraction of the file's UV area covered twice (1 without UVs).
    pub uv_overlap_read: f64,
    /// Charts of the new UVs (none when the file's were kept).
    pub charts: Option<usize>,
    /// Mean distance from each worn vertex to where unwinding left it on the canonical body, m.
    pub unposed_mean_m: f64,
    /// The drape's gates and figures.
    pub drape: SewingReport,
}

/// Makes `mesh`, worn by the body `shaped` posed by `frame`, a template on `model`'s default
/// body in its canonical pose. A mesh that cannot be repaired, or one that the engine cannot
/// drape, is an error naming the fault; a drape whose gates fail is reported, not raised.
pub fn import_garment(
    model: &BodyModel,
    mesh: &Garment,
    shaped: &ShapedBody,
    frame: &FramePose,
    options: &ImportOptions,
) -> Result<(Garment, ImportReport)> {
    let (vertices_read, triangles_read) = (mesh.positions.len(), mesh.triangles.len());
    let uv_overlap_read = garments::uv_overlap(mesh);
    let mut g = mesh.clone();
    if g.panels.is_empty() {
        g.panels.push(g.name.clone());
        g.triangle_panels = vec![0; g.triangles.len()];
    }
    for p in &mut g.positions {
        *p = p.map(|c| c * options.scale);
    }
    let welded = garments::weld(&mut g, options.weld_m);
    // Without UVs the repairs refuse the mesh; one UV per vertex stands in until the unwrap.
    let needs_uvs = g.uv_triangles.len() != g.triangles.len();
    if needs_uvs {
        g.uvs = vec![[0.0; 2]; g.positions.len()];
        g.uv_triangles = g.triangles.clone();
    }
    let (mut g, repairs) = garments::repair(&g, 1.0)?;
    let mut subdivisions = 0;
    while garments::median_edge_length(&g) > 2.0 * options.edge_length_m {
        if 4 * g.positions.len() > garments::MAX_TEMPLATE_VERTICES {
            return Err(Error::TooCoarse {
                garment: g.name.clone(),
                median_edge_cm: 100.0 * garments::median_edge_length(&g),
                max_vertices: garments::MAX_TEMPLATE_VERTICES,
            });
        }
        garments::subdivide(&mut g);
        subdivisions += 1;
    }
    let uvs = if needs_uvs {
        "none"
    } else if garments::uv_overlap(&g) > options.max_uv_overlap {
        "overlapping"
    } else {
        "kept"
    };
    let worn = g.positions.clone();
    scaled_about_centroid(&mut g.positions, options.rest_shrink);
    let bodies = unwinding_bodies(model, shaped, frame)?;
    let unwound = sim::unwind::unwind(
        model,
        &g.positions,
        &g.triangles,
        &worn,
        &bodies,
        &options.sewing,
    )?;
    // The canonical body at the frame's root translation, moved to the origin.
    let start: Vec<[f64; 3]> = unwound
        .iter()
        .map(|p| [0, 1, 2].map(|k| p[k] - frame.transl[k]))
        .collect();
    let unposed_mean_m = worn
        .iter()
        .zip(&start)
        .map(|(a, b)| (0..3).map(|k| (a[k] - b[k]).powi(2)).sum::<f64>().sqrt())
        .sum::<f64>()
        / worn.len().max(1) as f64;
    let (mut template, drape) = settle_on_body(model, &g, &start, &options.sewing)?;
    // Panels are cut on the canonical body, where the template rests.
    let charts = if uvs == "kept" {
        None
    } else {
        let guide = panel_guide(model, &template.positions, &template.triangles)?;
        Some(garments::unwrap_uvs(&mut template, &guide)?)
    };
    let report = ImportReport {
        vertices_read,
        triangles_read,
        welded,
        repairs,
        subdivisions,
        median_edge_m: garments::median_edge_length(&template),
        uvs: uvs.to_string(),
        uv_overlap_read,
        charts,
        unposed_mean_m,
        drape,
    };
    Ok((template, report))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_rest_shape_shrinks_about_its_centroid() {
        let mut points = vec![
            [0.0, 0.0, 0.0],
            [1.0, 0.0, 0.0],
            [0.0, 2.0, 0.0],
            [1.0, 2.0, 4.0],
        ];
        let before = points.clone();
        scaled_about_centroid(&mut points, 0.5);
        let centroid =
            |p: &[[f64; 3]]| [0, 1, 2].map(|k| p.iter().map(|x| x[k]).sum::<f64>() / 4.0);
        assert_eq!(centroid(&points), centroid(&before));
        let length = |p: &[[f64; 3]], i: usize, j: usize| {
            (0..3)
                .map(|k| (p[i][k] - p[j][k]).powi(2))
                .sum::<f64>()
                .sqrt()
        };
        for (i, j) in [(0, 1), (1, 2), (2, 3), (0, 3)] {
            assert!((length(&points, i, j) - 0.5 * length(&before, i, j)).abs() < 1e-12);
        }
    }
}
