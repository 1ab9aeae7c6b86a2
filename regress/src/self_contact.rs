//! Self-contact scenarios: layers dropped on each other keep the self-contact distance, a
//! sheet folded over itself on the ground does not pass through, and friction between layers
//! follows Coulomb's law (a patch on a tilted pinned sheet sticks iff tan(theta) <= mu, else
//! slides with a = g (sin theta - mu cos theta)). Each scene takes the self-contact switch, so
//! the tests can show that the checks fail without it.

use super::{G, Outcome};
use crate::error::Result;
use sim::count_self_intersections;
use sim::obstacles::{Obstacles, Plane};
use sim::{ClothMesh, ClothState, Vec3};
use sim::{ClothSetup, Solver};
use sim::{Material, SolverParams};

const FRAME: f64 = 1.0 / 30.0;

/// Friction coefficient between the layers of the friction scenes.
pub const LAYER_FRICTION: f64 = 0.3;

/// The scenario: the four measures with self-contact on.
pub fn self_contact(_long: bool) -> Result<Vec<Outcome>> {
    let distance = SolverParams::default().self_contact_distance;
    let (gap, crossings) = two_sheets(true)?;
    let (fold_gap, fold_crossings) = folded_strip(true)?;
    let mu = LAYER_FRICTION;
    let stick = patch_on_tilted_sheet((mu - 0.05).atan(), mu)?;
    let theta = (mu + 0.05).atan();
    let slide = patch_on_tilted_sheet(theta, mu)?;
    let expected = 0.5 * G * (theta.sin() - mu * theta.cos());
    Ok(vec![
        Outcome::new(
            "self_contact_sheets_gap",
            distance * 1e3,
            gap * 1e3,
            0.25 * distance * 1e3,
            "mm",
        ),
        Outcome::new(
            "self_contact_sheets_crossings",
            0.0,
            crossings as f64,
            0.0,
            "triangle pairs",
        ),
        Outcome::new(
            "self_contact_fold_crossings",
            0.0,
            fold_crossings as f64,
            0.0,
            "triangle pairs",
        ),
        Outcome::new(
            "self_contact_fold_gap_above_quarter_distance",
            1.0,
            (fold_gap > 0.25 * distance) as u8 as f64,
            0.0,
            "1 = yes",
        ),
        Outcome::new("self_contact_layer_stick_drift", 0.0, stick, 1e-6, "m"),
        Outcome::new(
            "self_contact_layer_slide_distance_1s",
            expected,
            slide,
            0.02 * expected,
            "m",
        ),
    ])
}

/// Both sheets of `meshes` in one cloth (vertex indices of the later ones shifted).
fn combine(meshes: &[(Vec<Vec3>, Vec<[u32; 3]>)]) -> Result<ClothMesh> {
    let mut positions = Vec::new();
    let mut triangles = Vec::new();
    for (p, t) in meshes {
        let base = positions.len() as u32;
        triangles.extend(t.iter().map(|t| t.map(|i| i + base)));
        positions.extend_from_slice(p);
    }
    Ok(ClothMesh::new(positions, triangles)?)
}

fn params(self_contact: bool) -> SolverParams {
    SolverParams {
        substeps: 4,
        max_iterations: 20,
        self_contact,
        ..SolverParams::default()
    }
}

/// A square sheet of `n` x `n` vertices, `size` wide, at height `y`, turned by `angle` about
/// the vertical.
fn sheet(n: usize, size: f64, y: f64, angle: f64) -> Result<(Vec<Vec3>, Vec<[u32; 3]>)> {
    let grid = ClothMesh::grid(n, size, y)?;
    let (s, c) = angle.sin_cos();
    let p = grid
        .rest()
        .iter()
        .map(|p| Vec3::new(c * p.x - s * p.z, p.y, s * p.x + c * p.z))
        .collect();
    Ok((p, grid.triangles().to_vec()))
}

/// Two sheets dropped on the ground, the smaller from 5 cm above the larger: (lowest gap
/// between the layers at the end, most self-intersections of a frame).
pub fn two_sheets(self_contact: bool) -> Result<(f64, usize)> {
    let lower = sheet(21, 0.4, 0.01, 0.0)?;
    let upper = sheet(15, 0.25, 0.06, 0.4)?;
    let split = lower.0.len();
    let mesh = combine(&[lower, upper])?;
    let mut solver = Solver::new(
        ClothSetup::new(mesh.clone(), Material::default()),
        params(self_contact),
        FRAME,
    )?;
    let mut state = ClothState::at_rest(mesh.rest().to_vec());
    let mut ground = Obstacles::ground(Plane::ground(0.0, 0.3));
    let mut crossings = 0;
    for k in 0..30 {
        solver.advance_frame(&mut state, &mut ground, k as f64 * FRAME, k)?;
        crossings = crossings.max(count_self_intersections(&state.positions, mesh.triangles()));
    }
    let lower_top = state.positions[..split]
        .iter()
        .map(|p| p.y)
        .fold(f64::NEG_INFINITY, f64::max);
    let upper_bottom = state.positions[split..]
        .iter()
        .map(|p| p.y)
        .fold(f64::INFINITY, f64::min);
    Ok((upper_bottom - lower_top, crossings))
}

/// A strip 10 cm wide and 51 cm long, folded over itself: 25 cm flat on the ground, a
/// half-circle of radius 2 cm, the last 19 cm flat 4 cm higher and thrown down at 1 m/s. Returns
/// (lowest gap between the layers over the last 10 frames, most self-intersections of a
/// frame).
pub fn folded_strip(self_contact: bool) -> Result<(f64, usize)> {
    let (columns, rows, spacing, radius, fold) = (52usize, 11usize, 0.01, 0.02, 0.25);
    let arc = std::f64::consts::PI * radius;
    let place = |s: f64| -> (f64, f64) {
        if s < fold {
            (s, 0.0)
        } else if s < fold + arc {
            let angle = (s - fold) / radius;
            (fold + radius * angle.sin(), radius * (1.0 - angle.cos()))
        } else {
            (fold - (s - fold - arc), 2.0 * radius)
        }
    };
    let mut positions = Vec::new();
    for i in 0..columns {
        let (x, y) = place(i as f64 * spacing);
        for j in 0..rows {
            positions.push(Vec3::new(x, y + 0.004, j as f64 * spacing));
        }
    }
    let id = |i: usize, j: usize| (i * rows + j) as u32;
    let mut triangles = Vec::new();
    for i in 0..columns - 1 {
        for j in 0..rows - 1 {
            triangles.push([id(i, j), id(i + 1, j), id(i + 1, j + 1)]);
            triangles.push([id(i, j), id(i + 1, j + 1), id(i, j + 1)]);
        }
    }
    let mesh = ClothMesh::new(positions.clone(), triangles)?;
    let mut solver = Solver::new(
        ClothSetup::new(mesh.clone(), Material::default()),
        params(self_contact),
        FRAME,
    )?;
    let mut state = ClothState::at_rest(positions);
    let top_layer = |i: usize| i as f64 * spacing > fold + arc + 0.02;
    let bottom_columns = (fold / spacing) as usize;
    // Height of each top-layer vertex over the bottom layer's row below it.
    let layer_gap = |x: &[Vec3]| -> f64 {
        let mut gap = f64::INFINITY;
        for i in (0..columns).filter(|&i| top_layer(i)) {
            for j in 0..rows {
                let p = x[i * rows + j];
                for k in 0..bottom_columns {
                    let (a, b) = (x[k * rows + j], x[(k + 1) * rows + j]);
                    if (a.x..b.x).contains(&p.x) {
                        let below = a.y + (b.y - a.y) * (p.x - a.x) / (b.x - a.x);
                        gap = gap.min(p.y - below);
                    }
                }
            }
        }
        gap
    };
    for (k, v) in state.velocities.iter_mut().enumerate() {
        if top_layer(k / rows) {
            v.y = -1.0;
        }
    }
    let mut ground = Obstacles::ground(Plane::ground(0.0, 0.3));
    let (mut crossings, mut gap) = (0, f64::INFINITY);
    for k in 0..45 {
        solver.advance_frame(&mut state, &mut ground, k as f64 * FRAME, k)?;
        let now = count_self_intersections(&state.positions, mesh.triangles());
        crossings = crossings.max(now);
        if k >= 35 {
            gap = gap.min(layer_gap(&state.positions));
        }
    }
    Ok((gap, crossings))
}

/// A stiff 2 cm patch resting on a pinned sheet tilted by `theta`, with friction `mu`
/// between them: how far the patch moves downhill in 1 s.
pub fn patch_on_tilted_sheet(theta: f64, mu: f64) -> Result<f64> {
    let normal = Vec3::new(theta.sin(), theta.cos(), 0.0);
    let downhill = Vec3::new(theta.cos(), -theta.sin(), 0.0);
    let distance = SolverParams::default().self_contact_distance;
    let tilt = |p: &Vec3, lift: f64| downhill * p.x + Vec3::z() * p.z + normal * lift;
    let base = ClothMesh::grid(11, 0.8, 0.0)?;
    let patch = ClothMesh::grid(3, 0.02, 0.0)?;
    let split = base.num_vertices();
    let mesh = combine(&[
        (
            base.rest().iter().map(|p| tilt(p, 0.0)).collect(),
            base.triangles().to_vec(),
        ),
        (
            patch
                .rest()
                .iter()
                .map(|p| tilt(&(p + Vec3::new(-0.25, 0.0, 0.013)), distance))
                .collect(),
            patch.triangles().to_vec(),
        ),
    ])?;
    let mut setup = ClothSetup::new(
        mesh.clone(),
        Material {
            stretch: 1000.0,
            density: 0.2,
            bending: 1e-6,
        },
    );
    setup.pins = (0..split as u32).collect();
    let solver_params = SolverParams {
        substeps: 10,
        max_iterations: 200,
        tolerance: 1e-12,
        self_friction: mu,
        ..params(true)
    };
    let mut solver = Solver::new(setup, solver_params, FRAME)?;
    let mut state = ClothState::at_rest(mesh.rest().to_vec());
    let start: Vec3 = state.positions[split..].iter().sum::<Vec3>() / 9.0;
    for k in 0..30 {
        solver.advance_frame(&mut state, &mut Obstacles::default(), k as f64 * FRAME, k)?;
    }
    let end: Vec3 = state.positions[split..].iter().sum::<Vec3>() / 9.0;
    let height = (end - start).dot(&normal);
    if height.abs() > 1e-3 {
        return Err(crate::error::Error::Scenario {
            scenario: "self_contact",
            problem: format!("the patch left the tilted sheet ({height} m along its normal)"),
        });
    }
    Ok((end - start).dot(&downhill))
}
