//! Scenarios of the free dynamics: free fall against the discrete formula, momentum and
//! energy conservation, determinism.

use super::{G, Outcome, advance};
use crate::error::Result;
use sim::constraints::{BendingRest, Seam};
use sim::obstacles::{Obstacles, Plane, Sphere};
use sim::{ClothMesh, ClothState, Vec3};
use sim::{ClothSetup, Solver};
use sim::{Material, SolverParams};

/// Free fall: exact discrete backward-Euler formula, relative error.
pub(super) fn free_fall(_long: bool) -> Result<Vec<Outcome>> {
    let mesh = ClothMesh::grid(5, 0.5, 1.0)?;
    let params = SolverParams {
        substeps: 10,
        max_iterations: 5,
        ..SolverParams::default()
    };
    let dt = 1.0 / 30.0;
    let mut solver = Solver::new(
        ClothSetup::new(mesh.clone(), Material::default()),
        params,
        dt,
    )?;
    let v0 = Vec3::new(0.3, 1.5, -0.2);
    let mut state = ClothState::at_rest(mesh.rest().to_vec());
    state.velocities.iter_mut().for_each(|v| *v = v0);
    let (h, g) = (dt / 10.0, Vec3::new(0.0, -G, 0.0));
    let mut worst: f64 = 0.0;
    for frame in 0..30 {
        solver.advance_frame(
            &mut state,
            &mut Obstacles::default(),
            frame as f64 * dt,
            frame,
        )?;
        let n = ((frame + 1) * 10) as f64;
        let (v, dx) = (v0 + n * h * g, n * h * v0 + g * h * h * n * (n + 1.0) / 2.0);
        for ((x, x0), vel) in state
            .positions
            .iter()
            .zip(mesh.rest())
            .zip(&state.velocities)
        {
            worst = worst
                .max((x - (x0 + dx)).norm() / dx.norm())
                .max((vel - v).norm() / v.norm());
        }
    }
    Ok(vec![Outcome::new(
        "free_fall_relative_error",
        0.0,
        worst,
        1e-10,
        "1",
    )])
}

fn scrambled(mesh: &ClothMesh) -> ClothState {
    let mut seed = 12345u64;
    let mut next = move || {
        seed = seed
            .wrapping_mul(6364136223846793005)
            .wrapping_add(1442695040888963407);
        ((seed >> 33) as f64 / (1u64 << 31) as f64) - 0.5
    };
    let mut state = ClothState::at_rest(mesh.rest().to_vec());
    for (x, v) in state.positions.iter_mut().zip(&mut state.velocities) {
        *x += 0.02 * Vec3::new(next(), next(), next());
        *v = Vec3::new(next(), next(), next());
    }
    state
}

fn elastic_setup(mesh: &ClothMesh, seams: bool) -> ClothSetup {
    let mut setup = ClothSetup::new(
        mesh.clone(),
        Material {
            stretch: 200.0,
            density: 0.3,
            bending: 1e-4,
        },
    );
    setup.bending_rest = BendingRest::Curved;
    if seams {
        setup.seams = vec![Seam {
            a: 0,
            b: mesh.num_vertices() as u32 - 1,
            stiffness: 50.0,
        }];
    }
    setup
}

/// Linear momentum without gravity, contact or damping, at 1, 3 and 20 iterations.
pub(super) fn momentum(_long: bool) -> Result<Vec<Outcome>> {
    let mesh = ClothMesh::grid(8, 0.5, 0.0)?;
    let mut worst: f64 = 0.0;
    for iterations in [1, 3, 20] {
        let params = SolverParams {
            substeps: 2,
            max_iterations: iterations,
            tolerance: 0.0,
            gravity: 0.0,
            ..SolverParams::default()
        };
        let mut solver = Solver::new(elastic_setup(&mesh, true), params, 1.0 / 30.0)?;
        solver.set_seam_length_cap(0.05);
        let mut state = scrambled(&mesh);
        let p = |s: &ClothState, m: &[f64]| -> Vec3 {
            s.velocities.iter().zip(m).map(|(v, m)| v * *m).sum()
        };
        let p0 = p(&state, solver.masses());
        let scale: f64 = state
            .velocities
            .iter()
            .zip(solver.masses())
            .map(|(v, m)| v.norm() * m)
            .sum();
        for frame in 0..20 {
            solver.advance_frame(
                &mut state,
                &mut Obstacles::default(),
                frame as f64 / 30.0,
                frame,
            )?;
            worst = worst.max((p(&state, solver.masses()) - p0).norm() / scale);
        }
    }
    Ok(vec![Outcome::new(
        "momentum_relative_drift",
        0.0,
        worst,
        1e-12,
        "1",
    )])
}

/// Total energy never grows once the iteration has converged (relative growth per frame).
pub(super) fn energy(_long: bool) -> Result<Vec<Outcome>> {
    let mesh = ClothMesh::grid(8, 0.5, 0.0)?;
    let params = SolverParams {
        substeps: 2,
        max_iterations: 1000,
        tolerance: 0.0,
        gravity: 0.0,
        ..SolverParams::default()
    };
    let mut solver = Solver::new(elastic_setup(&mesh, false), params, 1.0 / 30.0)?;
    let mut state = scrambled(&mesh);
    let mut e = solver.kinetic_energy(&state) + solver.elastic_energy(&state.positions);
    let mut growth: f64 = 0.0;
    for frame in 0..20 {
        solver.advance_frame(
            &mut state,
            &mut Obstacles::default(),
            frame as f64 / 30.0,
            frame,
        )?;
        let next = solver.kinetic_energy(&state) + solver.elastic_energy(&state.positions);
        growth = growth.max((next - e) / e);
        e = next;
    }
    Ok(vec![Outcome::new(
        "energy_growth_per_frame",
        0.0,
        growth.max(0.0),
        1e-6,
        "1 (relative)",
    )])
}

/// Same inputs, same bits.
pub(super) fn determinism(_long: bool) -> Result<Vec<Outcome>> {
    let run = || -> Result<Vec<Vec3>> {
        let mesh = ClothMesh::grid(20, 1.0, 0.6)?;
        let mut solver = Solver::new(
            ClothSetup::new(mesh.clone(), Material::default()),
            SolverParams::default(),
            1.0 / 30.0,
        )?;
        let sphere = Sphere::new(Vec3::new(0.0, 0.3, 0.0), 0.25, 0.3);
        let mut obstacles = Obstacles {
            ground: Some(Plane::ground(0.0, 0.5)),
            ..Obstacles::props(vec![Box::new(sphere)])
        };
        let mut state = ClothState::at_rest(mesh.rest().to_vec());
        advance(&mut solver, &mut state, &mut obstacles, 0..20, 1.0 / 30.0)?;
        Ok(state.positions)
    };
    let (a, b) = (run()?, run()?);
    let differing = a
        .iter()
        .zip(&b)
        .flat_map(|(p, q)| {
            p.iter()
                .zip(q.iter())
                .map(|(x, y)| x.to_bits() != y.to_bits())
        })
        .filter(|d| *d)
        .count();
    Ok(vec![Outcome::new(
        "determinism_differing_values",
        0.0,
        differing as f64,
        0.0,
        "coordinates",
    )])
}
