//! Scenarios of Coulomb friction: stick and slide on an incline, Ly et al.'s drop onto a
//! plane, a patch on an accelerating plate.

use super::{G, Outcome, advance, mean};
use crate::error::Result;
use sim::obstacles::{Obstacles, Plane};
use sim::{ClothMesh, ClothState, Vec3};
use sim::{ClothSetup, Solver};
use sim::{Material, SolverParams};

/// Solver, state, obstacles, downhill direction and plane normal of an incline scene.
type Incline = (Solver, ClothState, Obstacles, Vec3, Vec3);

/// A small stiff patch on an incline through the origin, tilted by theta about z.
fn patch_on_incline(theta: f64, mu: f64, substeps: usize, frame_dt: f64) -> Result<Incline> {
    let grid = ClothMesh::grid(3, 0.02, 0.0)?;
    let normal = Vec3::new(theta.sin(), theta.cos(), 0.0);
    let downhill = Vec3::new(theta.cos(), -theta.sin(), 0.0);
    let positions: Vec<Vec3> = grid
        .rest()
        .iter()
        .map(|p| downhill * p.x + Vec3::z() * p.z)
        .collect();
    let mesh = ClothMesh::new(positions.clone(), grid.triangles().to_vec())?;
    let params = SolverParams {
        substeps,
        max_iterations: 200,
        tolerance: 1e-12,
        contact_offset: 0.0,
        ..SolverParams::default()
    };
    let solver = Solver::new(
        ClothSetup::new(
            mesh,
            Material {
                stretch: 1000.0,
                density: 0.2,
                bending: 1e-6,
            },
        ),
        params,
        frame_dt,
    )?;
    let plane = Obstacles::props(vec![Box::new(Plane::new(Vec3::zeros(), normal, mu))]);
    Ok((
        solver,
        ClothState::at_rest(positions),
        plane,
        downhill,
        normal,
    ))
}

/// Stick at mu = tan + 0.05 (drift), slide at tan - 0.05 (acceleration).
pub(super) fn incline(_long: bool) -> Result<Vec<Outcome>> {
    let theta = 30f64.to_radians();
    let dt = 1.0 / 30.0;
    let (mut solver, mut state, mut obstacles, _, _) =
        patch_on_incline(theta, theta.tan() + 0.05, 4, dt)?;
    let start = mean(&state.positions);
    advance(&mut solver, &mut state, &mut obstacles, 0..30, dt)?;
    let drift = (mean(&state.positions) - start).norm();
    let mu = theta.tan() - 0.05;
    let (mut solver, mut state, mut obstacles, downhill, _) = patch_on_incline(theta, mu, 4, dt)?;
    advance(&mut solver, &mut state, &mut obstacles, 0..10, dt)?;
    let v10 = mean(&state.velocities).dot(&downhill);
    advance(&mut solver, &mut state, &mut obstacles, 10..30, dt)?;
    let accel = (mean(&state.velocities).dot(&downhill) - v10) / (20.0 * dt);
    let expected = G * (theta.sin() - mu * theta.cos());
    Ok(vec![
        Outcome::new("incline_stick_drift_1s", 0.0, drift, 1e-6, "m"),
        Outcome::new(
            "incline_slide_acceleration",
            expected,
            accel,
            0.01 * expected,
            "m/s^2",
        ),
    ])
}

/// Ly et al. 2020, Fig. 5: drop from 0.2 m onto a 45 degree plane, mu 0.1, h = 1 ms.
pub(super) fn ly2020_drop(_long: bool) -> Result<Vec<Outcome>> {
    let dt = 1e-3;
    let (mut solver, mut state, mut obstacles, downhill, normal) =
        patch_on_incline(45f64.to_radians(), 0.1, 1, dt)?;
    for p in &mut state.positions {
        *p += Vec3::new(0.0, 0.2, 0.0);
    }
    let mut impact = None;
    let mut after_impact = 0.0;
    let mut samples = Vec::new();
    for k in 0..500 {
        solver.advance_frame(&mut state, &mut obstacles, k as f64 * dt, k)?;
        let t = (k + 1) as f64 * dt;
        let v = mean(&state.velocities);
        if impact.is_none() && t > 0.1 && v.dot(&normal).abs() < 1e-6 {
            impact = Some(t);
            after_impact = v.dot(&downhill);
        }
        samples.push((t, v));
    }
    let impact = impact.unwrap_or(f64::NAN);
    let speed = |t: f64| {
        samples[((t / dt).round() as usize).saturating_sub(1)]
            .1
            .dot(&downhill)
    };
    let accel = (speed(0.5) - speed(0.35)) / 0.15;
    Ok(vec![
        Outcome::new("ly2020_impact_time", 0.2019, impact, 0.0015, "s"),
        Outcome::new(
            "ly2020_tangential_speed_after_impact",
            1.2606,
            after_impact,
            0.01 * 1.2606,
            "m/s",
        ),
        Outcome::new(
            "ly2020_acceleration_after_impact",
            6.243,
            accel,
            0.01 * 6.243,
            "m/s^2",
        ),
        Outcome::new(
            "ly2020_speed_at_0.5s",
            3.122,
            speed(0.5),
            0.01 * 3.122,
            "m/s",
        ),
    ])
}

/// A cloth patch on a horizontally accelerating plate sticks iff a <= mu g.
pub(super) fn accelerating_plate(_long: bool) -> Result<Vec<Outcome>> {
    let mu = 0.5;
    let dt = 1.0 / 30.0;
    let mut out = Vec::new();
    for (factor, name) in [
        (0.8, "plate_stick_below_mu_g"),
        (1.5, "plate_slide_above_mu_g"),
    ] {
        let mesh = ClothMesh::grid(3, 0.02, 0.0)?;
        let params = SolverParams {
            substeps: 4,
            max_iterations: 200,
            tolerance: 1e-12,
            contact_offset: 0.0,
            ..SolverParams::default()
        };
        let mut solver = Solver::new(
            ClothSetup::new(
                mesh.clone(),
                Material {
                    stretch: 1000.0,
                    density: 0.2,
                    bending: 1e-6,
                },
            ),
            params,
            dt,
        )?;
        let mut plate = Plane::ground(0.0, mu);
        let a = factor * mu * G;
        plate.motion.acceleration = Vec3::new(a, 0.0, 0.0);
        let mut obstacles = Obstacles::ground(plate);
        let mut state = ClothState::at_rest(mesh.rest().to_vec());
        let start = mean(&state.positions);
        advance(&mut solver, &mut state, &mut obstacles, 0..15, dt)?;
        let v1 = mean(&state.velocities).x;
        advance(&mut solver, &mut state, &mut obstacles, 15..30, dt)?;
        let _ = start;
        if factor < 1.0 {
            // Sticking: the cloth moves with the plate, whose velocity after 1 s is a.
            let slip = (mean(&state.velocities).x - a).abs();
            out.push(Outcome::new(
                name,
                0.0,
                slip,
                1e-6,
                "m/s (cloth speed relative to the plate at 1 s)",
            ));
        } else {
            let accel = (mean(&state.velocities).x - v1) / 0.5;
            out.push(Outcome::new(
                name,
                mu * G,
                accel,
                0.01 * mu * G,
                "m/s^2 (cloth acceleration = mu g)",
            ));
        }
    }
    Ok(out)
}
