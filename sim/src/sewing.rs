//! Sewing: a meshed GarmentCode pattern becomes a template draped on the default body.
//!
//! 1. Fit: GarmentCode places panels for its average SMPL body standing with feet at y = 0
//!    (cm, y up, facing +z). Positions are mapped onto our canonical body: heights scale with
//!    body height from the feet, and the torso's front-back centre is aligned
//!    ([`fit_to_body`]).
//! 2. Close: seam springs whose gap cap is lowered linearly from the largest initial gap to 0
//!    over `close_frames` (so no seam closes faster than that), gravity off, strong air
//!    damping, the body colliding, until every stitched pair is within half the seam gate.
//! 3. Untangle: creases that closing folded through themselves are smoothed open
//!    ([`crate::untangle`]); closing runs without cloth-cloth contact, which would hold
//!    panels that start apart from meeting.
//! 4. Settle: cloth-cloth contact on, gravity on, damping 6/s, four substeps, until at most
//!    1.5% of vertices moved more than 1 cm/s on average over the last 10 frames (net
//!    displacement, so the contact solver's frame-to-frame noise does not count), or the
//!    frame budget runs out.
//! 5. Merge: stitched pairs become one vertex; the merged, draped mesh is the template.
//!
//! The gates are GarmentCode's: static equilibrium (moving fraction <= 1.5%), cloth-body
//! intersections (<= 35 vertices inside), seam gaps (< 2 mm before merging),
//! self-intersections (<= 300 crossing triangle pairs); the report also carries the largest
//! edge stretch and the timings.

use std::collections::VecDeque;
use std::time::Instant;

use garments::{Garment, SewnMesh};
use motions::BodyModel;
use serde::{Deserialize, Serialize};

use crate::cloth::{ClothMesh, ClothState, Vec3};
use crate::constraints::Seam;
use crate::error::{Error, Result};
use crate::obstacles::{AnimatedMesh, Obstacles};
use crate::params::{Material, SolverParams};
use crate::scene::{FPS, canonical_body, edge_stretch};
use crate::self_intersection::count_self_intersections;
use crate::solver::{ClothSetup, Solver};
use crate::untangle::{UntangleReport, untangle};

/// Height of GarmentCode's average body (f_smpl_average_A40.obj), m.
pub const PATTERN_BODY_HEIGHT_M: f64 = 1.6584;
/// Front-back centre of that body's torso ([`torso_centre_z`]), m.
pub const PATTERN_BODY_TORSO_Z_M: f64 = 0.0179;

/// Half-widths of that body's legs and hips (largest |x| of the vertices with |x| < 0.35 m
/// within 1 cm of the height) at 5%, 10%, ..., 60% of its height, m ([`half_widths`]).
pub const PATTERN_BODY_HALF_WIDTHS: [f64; 12] = [
    0.1307, 0.1168, 0.1504, 0.1579, 0.1508, 0.1477, 0.1611, 0.1748, 0.1926, 0.1924, 0.1837, 0.1572,
];
/// Largest horizontal grading factor.
pub const MAX_GRADE: f64 = 1.4;

/// Gate: at most this fraction of vertices still moving.
pub const MAX_MOVING_FRACTION: f64 = 0.015;
/// Average speed above which a vertex counts as moving, m/s.
pub const MOVING_SPEED: f64 = 0.01;
/// Frames the average speed is taken over (net displacement / time).
pub const MOVING_WINDOW: usize = 10;
/// Gate: at most this many vertices inside the body.
pub const MAX_VERTS_INSIDE: usize = 35;
/// Gate: stitched vertices closer than this before merging, m.
pub const MAX_SEAM_GAP_M: f64 = 0.002;
/// Gate: at most this many crossing triangle pairs in the template.
pub const MAX_SELF_INTERSECTIONS: usize = 300;

/// How a pattern is sewn and draped.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct SewingOptions {
    /// Cloth material while draping.
    pub material: Material,
    /// Cloth-body friction.
    pub friction: f64,
    /// Seam spring stiffness, N/m.
    pub seam_stiffness: f64,
    /// Frames over which the seams ramp closed.
    pub close_frames: usize,
    /// Most frames for closing (ramp included) before settling starts regardless.
    pub max_close_frames: usize,
    /// Frames of settling at least / at most.
    pub min_settle_frames: usize,
    /// Most settling frames.
    pub max_settle_frames: usize,
    /// Air damping while settling, 1/s.
    pub settle_damping: f64,
}

impl Default for SewingOptions {
    fn default() -> Self {
        Self {
            material: Material::default(),
            friction: 0.3,
            seam_stiffness: 500.0,
            close_frames: 30,
            max_close_frames: 90,
            min_settle_frames: 30,
            max_settle_frames: 240,
            settle_damping: 6.0,
        }
    }
}

/// What sewing measured: the gates and their figures.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct SewingReport {
    /// All gates passed.
    pub gates_passed: bool,
    /// Template vertices (merged).
    pub vertices: usize,
    /// Template triangles.
    pub triangles: usize,
    /// Template vertices inside the body at the end.
    pub verts_inside: usize,
    /// Deepest template vertex inside the body, m.
    pub max_penetration_m: f64,
    /// Largest stitched-pair distance just before merging, m.
    pub max_seam_gap_m: f64,
    /// Fraction of vertices whose average speed over the last 10 frames exceeds 1 cm/s.
    pub moving_fraction: f64,
    /// Largest edge length over its flat-pattern rest length.
    pub max_edge_stretch: f64,
    /// Crossing triangle pairs of the template.
    pub self_intersections: usize,
    /// Frames spent closing seams and settling.
    pub close_frames: usize,
    /// Crossing triangle pairs when the seams had closed (stitched vertices counted as one).
    pub crossings_closed: usize,
    /// Crossing triangle pairs left after untangling, before settling.
    pub crossings_untangled: usize,
    /// Settling frames.
    pub settle_frames: usize,
    /// Wall time of the simulation, s.
    pub drape_s: f64,
    /// Which gates failed, in words (empty when all passed).
    pub failed: Vec<String>,
}

/// Untangles `state` ([`untangle`]) as the merged mesh: stitched vertices move as one, by
/// the displacement of their mean, and moved vertices come to rest.
fn untangle_seamed(state: &mut ClothState, sewn: &SewnMesh) -> UntangleReport {
    let n = state.positions.len();
    let root = sewn.stitched_roots();
    let mut mean = vec![Vec3::zeros(); n];
    let mut count = vec![0usize; n];
    for (v, p) in state.positions.iter().enumerate() {
        mean[root[v] as usize] += p;
        count[root[v] as usize] += 1;
    }
    for (m, &c) in mean.iter_mut().zip(&count) {
        if c > 0 {
            *m /= c as f64;
        }
    }
    let start = mean.clone();
    // Triangles that collapse when merged (dart tips) are left out, as merging drops them.
    let triangles: Vec<[u32; 3]> = sewn
        .garment
        .triangles
        .iter()
        .map(|t| t.map(|v| root[v as usize]))
        .filter(|[a, b, c]| a != b && b != c && a != c)
        .collect();
    let report = untangle(&mut mean, &triangles);
    for (v, r) in root.iter().enumerate() {
        let moved = mean[*r as usize] - start[*r as usize];
        if moved != Vec3::zeros() {
            state.positions[v] += moved;
            state.velocities[v] = Vec3::zeros();
        }
    }
    report
}

/// Lowest and highest y of a vertex set.
fn height_range(vertices: &[[f64; 3]]) -> (f64, f64) {
    vertices
        .iter()
        .fold((f64::INFINITY, f64::NEG_INFINITY), |(l, h), v| {
            (l.min(v[1]), h.max(v[1]))
        })
}

/// Front-back centre of a body's torso: the mid-depth of the central strip (|x| < 10 cm) at
/// 60-80% of the height, averaged. `vertices` y up, facing +z.
pub fn torso_centre_z(vertices: &[[f64; 3]]) -> f64 {
    let (lo, hi) = height_range(vertices);
    let mut sum = 0.0;
    let mut count = 0;
    for k in 0..5 {
        let y = lo + (0.6 + 0.05 * k as f64) * (hi - lo);
        let (zmin, zmax) = vertices
            .iter()
            .filter(|v| (v[1] - y).abs() < 0.01 && v[0].abs() < 0.1)
            .fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), v| {
                (a.min(v[2]), b.max(v[2]))
            });
        if zmin.is_finite() {
            sum += (zmin + zmax) / 2.0;
            count += 1;
        }
    }
    if count == 0 { 0.0 } else { sum / count as f64 }
}

/// Half-widths of a body's legs and hips at 5%, 10%, ..., 60% of its height (see
/// [`PATTERN_BODY_HALF_WIDTHS`]).
pub fn half_widths(vertices: &[[f64; 3]]) -> [f64; 12] {
    let (lo, hi) = height_range(vertices);
    std::array::from_fn(|k| {
        let y = lo + 0.05 * (k + 1) as f64 * (hi - lo);
        vertices
            .iter()
            .filter(|v| (v[1] - y).abs() < 0.01 && v[0].abs() < 0.35)
            .fold(0.0, |a: f64, v| a.max(v[0].abs()))
    })
}

/// Horizontal grading factor at each tabulated height: how much wider `body` is than
/// GarmentCode's body, in [1, MAX_GRADE], never smaller lower down (a skirt must pass the
/// widest part below it), constant below 20% of the height (feet).
fn grades(body: &[[f64; 3]]) -> [f64; 12] {
    let ours = half_widths(body);
    let mut g: [f64; 12] = std::array::from_fn(|k| {
        let k = k.max(3);
        (ours[k] / PATTERN_BODY_HALF_WIDTHS[k]).clamp(1.0, MAX_GRADE)
    });
    for k in (0..11).rev() {
        g[k] = g[k].max(g[k + 1]);
    }
    g
}

/// Maps a pattern placed for GarmentCode's body (feet at y = 0, metres) onto `body` (the
/// canonical body's vertices): heights scale with body height from the feet, z moves by the
/// difference of the torso centres, and below the hips x widens where `body` is wider
/// ([`grades`]: the pattern is graded, so its rest shape changes too).
pub fn fit_to_body(positions: &[[f64; 3]], body: &[[f64; 3]]) -> Vec<[f64; 3]> {
    let (feet, top) = height_range(body);
    let scale = (top - feet) / PATTERN_BODY_HEIGHT_M;
    let dz = torso_centre_z(body) - PATTERN_BODY_TORSO_Z_M;
    let grade = grades(body);
    positions
        .iter()
        .map(|p| {
            // Tabulated at fractions 0.05 (k = 0) .. 0.60 (k = 11), linear in between.
            let f = (p[1] / PATTERN_BODY_HEIGHT_M / 0.05 - 1.0).clamp(0.0, 11.0);
            let k = (f.floor() as usize).min(10);
            let g = grade[k] + (grade[k + 1] - grade[k]) * (f - k as f64);
            [p[0] * g, feet + p[1] * scale, p[2] + dz]
        })
        .collect()
}

/// Checks that `sewn` can be simulated at all, before anything is draped: the cloth mesh
/// builds and its system factorizes (what `garments check` runs on a pattern, so that a
/// pattern it passes does not fail `garments make` in the solver).
pub fn preflight(model: &BodyModel, sewn: &SewnMesh, options: &SewingOptions) -> Result<()> {
    first_solver(model, sewn, options, Placement::PatternFrame).map(|_| ())
}

/// Where the garment's positions are when draping starts.
#[derive(Debug, Clone, Copy, PartialEq)]
enum Placement<'a> {
    /// In GarmentCode's frame, fitted to the body by [`fit_to_body`].
    PatternFrame,
    /// Already on the canonical body (a mesh imported and unposed): its positions are its rest
    /// shape, and it starts at `start`.
    OnTheBody {
        /// Where each vertex starts, m.
        start: &'a [[f64; 3]],
    },
}

/// The garment placed on the canonical body and the solver that closes its seams.
struct FirstSolver {
    body: motions::PosedBody,
    rest: Vec<Vec3>,
    mesh: ClothMesh,
    solver: Solver,
    params: SolverParams,
}

/// Places the garment on the canonical body and factorizes the system that closes its seams.
fn first_solver(
    model: &BodyModel,
    sewn: &SewnMesh,
    options: &SewingOptions,
    placement: Placement,
) -> Result<FirstSolver> {
    let body = canonical_body(model)?;
    let placed = match placement {
        Placement::PatternFrame => fit_to_body(&sewn.garment.positions, &body.vertices),
        Placement::OnTheBody { .. } => sewn.garment.positions.clone(),
    };
    let rest: Vec<Vec3> = placed.iter().map(|p| Vec3::new(p[0], p[1], p[2])).collect();
    let mesh = ClothMesh::new(rest.clone(), sewn.garment.triangles.clone())?;
    let mut setup = ClothSetup::new(mesh.clone(), options.material);
    setup.seams = sewn
        .stitch_pairs
        .iter()
        .map(|&[a, b]| Seam {
            a,
            b,
            stiffness: options.seam_stiffness,
        })
        .collect();
    let params = SolverParams {
        // Four substeps: at two, contact on light cloth does not converge well enough for
        // the static-equilibrium gate (measured on shirt_mean: 5% drifting, 100+ inside).
        // 40 iterations: at 20, dress_tshirt kept drifting (11.7% moving) and
        // longsleeve_fitted kept 58 vertices inside; a template is made once and cached.
        substeps: 4,
        max_iterations: 40,
        ..SolverParams::default()
    };
    let solver = Solver::new(setup, params, 1.0 / FPS)?;
    Ok(FirstSolver {
        body,
        rest,
        mesh,
        solver,
        params,
    })
}

/// Sews `sewn` (positions in GarmentCode's frame, metres) onto the default shape of `model` in
/// its canonical pose and drapes it: the template and the report. Gates that fail are
/// reported, not raised: the caller decides.
pub fn sew(
    model: &BodyModel,
    sewn: &SewnMesh,
    options: &SewingOptions,
) -> Result<(Garment, SewingReport)> {
    sew_placed(model, sewn, options, Placement::PatternFrame)
}

/// Drapes `garment` on the default shape of `model` in its canonical pose (a mesh imported and
/// unposed) as [`sew`] drapes a sewn pattern after its seams close: settled under gravity with
/// cloth-cloth contact, its crossings untangled first, with the same gates. Its rest shape is
/// `garment`'s positions; it starts at `start` (one position per vertex).
pub fn settle_on_body(
    model: &BodyModel,
    garment: &Garment,
    start: &[[f64; 3]],
    options: &SewingOptions,
) -> Result<(Garment, SewingReport)> {
    if start.len() != garment.positions.len() {
        return Err(Error::Garment {
            garment: garment.name.clone(),
            problem: format!(
                "{} start positions for {} vertices",
                start.len(),
                garment.positions.len()
            ),
        });
    }
    let unsewn = SewnMesh {
        garment: garment.clone(),
        stitch_pairs: Vec::new(),
    };
    sew_placed(model, &unsewn, options, Placement::OnTheBody { start })
}

/// Stages: the first solver, the seams closed, crossings untangled, settled with cloth-cloth
/// contact, the seams merged, the gates.
fn sew_placed(
    model: &BodyModel,
    sewn: &SewnMesh,
    options: &SewingOptions,
    placement: Placement,
) -> Result<(Garment, SewingReport)> {
    let started = Instant::now();
    let FirstSolver {
        body,
        rest,
        mesh,
        mut solver,
        params,
    } = first_solver(model, sewn, options, placement)?;
    let body_vertices: Vec<Vec3> = body
        .vertices
        .iter()
        .map(|p| Vec3::new(p[0], p[1], p[2]))
        .collect();
    let body_obstacle = AnimatedMesh::new(&body_vertices, model.faces(), options.friction)?;
    let mut obstacles = Obstacles::body(body_obstacle);
    let mut state = ClothState::at_rest(rest);
    if let Placement::OnTheBody { start } = placement {
        state.positions = start.iter().map(|p| Vec3::new(p[0], p[1], p[2])).collect();
    }
    let close_frames = close_seams(&mut solver, &mut state, &mut obstacles, sewn, options)?;
    // Open the creases closing left crossed, then settle with cloth-cloth contact so the
    // layers stay apart (with contact from the start, panels that start apart cannot close).
    let untangled = untangle_seamed(&mut state, sewn);
    let mut solver = Solver::new(
        solver.setup().clone(),
        SolverParams {
            self_contact: true,
            ..params
        },
        1.0 / FPS,
    )?;
    solver.set_seam_length_cap(0.0);
    solver.set_gravity_and_damping(SolverParams::default().gravity, options.settle_damping);
    let (settle_frames, moving_fraction) = settle(
        &mut solver,
        &mut state,
        &mut obstacles,
        options,
        close_frames,
    )?;
    let max_seam_gap_m = sewn.max_seam_gap(&plain(&state));
    let (max_edge_stretch, _) = edge_stretch(&mesh, &state.positions);
    let template = sewn.merged(&plain(&state)).map_err(|e| Error::Garment {
        garment: sewn.garment.name.clone(),
        problem: format!("merging seams: {e}"),
    })?;
    let body_mesh = obstacles.body.as_mut().ok_or_else(|| Error::Obstacle {
        obstacle: "body".into(),
        problem: "missing from the sewing scene".into(),
    })?;
    let report = SewingReport {
        max_edge_stretch,
        close_frames,
        crossings_closed: untangled.before,
        crossings_untangled: untangled.after,
        settle_frames,
        drape_s: started.elapsed().as_secs_f64(),
        ..gates(body_mesh, &template, moving_fraction, max_seam_gap_m)
    };
    Ok((template, report))
}

/// The cloth's positions as plain arrays.
fn plain(state: &ClothState) -> Vec<[f64; 3]> {
    state.positions.iter().map(|p| [p.x, p.y, p.z]).collect()
}

/// Closes the seams: no gravity, strong damping, the gap cap lowered linearly to 0. Returns the
/// frames it took (none without seams).
fn close_seams(
    solver: &mut Solver,
    state: &mut ClothState,
    obstacles: &mut Obstacles,
    sewn: &SewnMesh,
    options: &SewingOptions,
) -> Result<usize> {
    let initial_gap = sewn.max_seam_gap(&plain(state));
    solver.set_gravity_and_damping(0.0, 5.0);
    let mut frame = 0;
    while frame < options.max_close_frames && !sewn.stitch_pairs.is_empty() {
        let ramp = (frame + 1) as f64 / options.close_frames.max(1) as f64;
        solver.set_seam_length_cap(initial_gap * (1.0 - ramp.min(1.0)));
        solver.advance_frame(state, obstacles, frame as f64 / FPS, frame)?;
        frame += 1;
        if frame >= options.close_frames && sewn.max_seam_gap(&plain(state)) < MAX_SEAM_GAP_M / 2.0
        {
            break;
        }
    }
    Ok(frame)
}

/// Settles from frame `first` until the cloth stops moving (at least `min_settle_frames`, at
/// most `max_settle_frames`). Moving = net displacement over the last MOVING_WINDOW frames
/// faster than MOVING_SPEED on average: drift, not the contact solver's frame-to-frame noise.
/// Returns the frames settled and the fraction of vertices still moving.
fn settle(
    solver: &mut Solver,
    state: &mut ClothState,
    obstacles: &mut Obstacles,
    options: &SewingOptions,
    first: usize,
) -> Result<(usize, f64)> {
    let mut history: VecDeque<Vec<Vec3>> = VecDeque::new();
    let moving = |history: &VecDeque<Vec<Vec3>>, state: &ClothState| {
        let Some(old) = history.front().filter(|_| history.len() == MOVING_WINDOW) else {
            return 1.0;
        };
        let reach = MOVING_SPEED * MOVING_WINDOW as f64 / FPS;
        state
            .positions
            .iter()
            .zip(old)
            .filter(|(p, q)| (*p - *q).norm() > reach)
            .count() as f64
            / state.positions.len() as f64
    };
    let (mut frame, mut settle_frames) = (first, 0);
    while settle_frames < options.max_settle_frames {
        if history.len() == MOVING_WINDOW {
            history.pop_front();
        }
        history.push_back(state.positions.clone());
        solver.advance_frame(state, obstacles, frame as f64 / FPS, frame)?;
        frame += 1;
        settle_frames += 1;
        if settle_frames >= options.min_settle_frames
            && moving(&history, state) <= MAX_MOVING_FRACTION
        {
            break;
        }
    }
    Ok((settle_frames, moving(&history, state)))
}

/// The drape's gates on the merged `template`: still moving, vertices inside the body, the
/// seam gap, crossing triangle pairs. The caller fills in what the earlier stages counted.
fn gates(
    body_mesh: &mut AnimatedMesh,
    template: &Garment,
    moving_fraction: f64,
    max_seam_gap_m: f64,
) -> SewingReport {
    let merged: Vec<Vec3> = template
        .positions
        .iter()
        .map(|p| Vec3::new(p[0], p[1], p[2]))
        .collect();
    let distances = body_mesh.measure(&merged, 0.03);
    let self_intersections = count_self_intersections(&merged, &template.triangles);
    let verts_inside = distances.iter().filter(|&&d| d < 0.0).count();
    let max_penetration_m = distances.iter().fold(0.0f64, |a, &d| a.max(-d));
    let mut failed = Vec::new();
    if moving_fraction > MAX_MOVING_FRACTION {
        failed.push(format!(
            "static equilibrium: {:.1}% of vertices moving (at most {:.1}%)",
            100.0 * moving_fraction,
            100.0 * MAX_MOVING_FRACTION
        ));
    }
    if verts_inside > MAX_VERTS_INSIDE {
        failed.push(format!(
            "cloth-body intersections: {verts_inside} vertices inside (at most {MAX_VERTS_INSIDE})"
        ));
    }
    if max_seam_gap_m >= MAX_SEAM_GAP_M {
        failed.push(format!(
            "seam gap {:.2} mm (under {:.1} mm)",
            1e3 * max_seam_gap_m,
            1e3 * MAX_SEAM_GAP_M
        ));
    }
    if self_intersections > MAX_SELF_INTERSECTIONS {
        failed.push(format!(
            "self-intersections: {self_intersections} crossing triangle pairs (at most \
             {MAX_SELF_INTERSECTIONS})"
        ));
    }
    SewingReport {
        gates_passed: failed.is_empty(),
        vertices: template.positions.len(),
        triangles: template.triangles.len(),
        verts_inside,
        max_penetration_m,
        max_seam_gap_m,
        moving_fraction,
        max_edge_stretch: 0.0,
        self_intersections,
        close_frames: 0,
        crossings_closed: 0,
        crossings_untangled: 0,
        settle_frames: 0,
        drape_s: 0.0,
        failed,
    }
}
