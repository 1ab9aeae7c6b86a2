//! Coulomb friction on an inclined plane (PHYSICS.md validation 3): a patch sticks iff
//! tan(theta) <= mu, otherwise it slides with a = g (sin theta - mu cos theta); and the drop
//! onto a 45 degree plane of Ly et al. 2020, Fig. 5.

use sim::obstacles::{Obstacle, Plane};
use sim::{ClothMesh, ClothSetup, ClothState, Material, Solver, SolverParams, Vec3};

const G: f64 = 9.81;

/// A small stiff patch lying on a plane through the origin tilted by `theta` about z (the
/// downhill direction is -x rotated). Returns the solver, state, obstacle and downhill unit
/// vector.
fn patch_on_incline(
    theta: f64,
    mu: f64,
    lift: f64,
    substeps: usize,
) -> (Solver, ClothState, Vec<Box<dyn Obstacle>>, Vec3, Vec3) {
    let mesh = ClothMesh::grid(3, 0.02, 0.0).unwrap();
    let normal = Vec3::new(theta.sin(), theta.cos(), 0.0);
    let downhill = Vec3::new(theta.cos(), -theta.sin(), 0.0);
    let side = Vec3::z();
    // Map the grid's x-z plane onto the incline, lifted along the normal.
    let positions: Vec<Vec3> = mesh
        .rest()
        .iter()
        .map(|p| downhill * p.x + side * p.z + normal * lift)
        .collect();
    let mesh = ClothMesh::new(positions.clone(), mesh.triangles().to_vec()).unwrap();
    let params = SolverParams {
        substeps,
        max_iterations: 200,
        tolerance: 1e-12,
        contact_offset: 0.0,
        ..SolverParams::default()
    };
    let material = Material {
        stretch: 1000.0,
        density: 0.2,
        bending: 1e-6,
    };
    let solver = Solver::new(ClothSetup::new(mesh, material), params, 1.0 / 30.0).unwrap();
    let plane: Box<dyn Obstacle> = Box::new(Plane::new(Vec3::zeros(), normal, mu));
    (
        solver,
        ClothState::at_rest(positions),
        vec![plane],
        downhill,
        normal,
    )
}

fn centroid(s: &ClothState) -> Vec3 {
    s.positions.iter().sum::<Vec3>() / s.positions.len() as f64
}

#[test]
fn sticks_when_mu_exceeds_the_slope() {
    let theta = 30f64.to_radians();
    let (mut solver, mut state, mut obstacles, _, _) =
        patch_on_incline(theta, theta.tan() + 0.05, 0.0, 4);
    let start = centroid(&state);
    for frame in 0..30 {
        solver
            .advance_frame(&mut state, &mut obstacles, frame as f64 / 30.0, frame)
            .unwrap();
    }
    let drift = (centroid(&state) - start).norm();
    assert!(
        drift < 1e-6,
        "drift over 1 s at mu = tan(theta) + 0.05: {drift:e} m (tolerance 1e-6 m)"
    );
}

#[test]
fn slides_with_the_coulomb_acceleration() {
    let theta = 30f64.to_radians();
    let mu = theta.tan() - 0.05;
    let (mut solver, mut state, mut obstacles, downhill, _) = patch_on_incline(theta, mu, 0.0, 4);
    let expected = G * (theta.sin() - mu * theta.cos());
    let mut speeds = Vec::new();
    for frame in 0..30 {
        solver
            .advance_frame(&mut state, &mut obstacles, frame as f64 / 30.0, frame)
            .unwrap();
        let v: Vec3 = state.velocities.iter().sum::<Vec3>() / state.velocities.len() as f64;
        speeds.push(v.dot(&downhill));
    }
    let measured = (speeds[29] - speeds[9]) / (20.0 / 30.0);
    let error = (measured / expected - 1.0).abs();
    assert!(
        error < 0.01,
        "acceleration {measured:.5} m/s^2, expected g(sin - mu cos) = {expected:.5} (tolerance 1%)"
    );
}

#[test]
fn drop_onto_a_45_degree_plane_matches_ly_2020() {
    // Drop from 0.2 m above the plane's contact point, mu = 0.1, h = 1 ms.
    let theta = 45f64.to_radians();
    let (mut solver, mut state, mut obstacles, downhill, normal) = {
        let (s, mut st, o, d, n) = patch_on_incline(theta, 0.1, 0.0, 33);
        for p in &mut st.positions {
            *p += Vec3::new(0.0, 0.2, 0.0);
        }
        (s, st, o, d, n)
    };
    let frame_dt = 1.0 / 30.0;
    let mut impact = None;
    let mut samples = Vec::new();
    let mut t = 0.0;
    for frame in 0..15 {
        // Sample every step through one-step frames: advance the frame, then look.
        solver
            .advance_frame(&mut state, &mut obstacles, t, frame)
            .unwrap();
        t += frame_dt;
        let v: Vec3 = state.velocities.iter().sum::<Vec3>() / state.velocities.len() as f64;
        samples.push((t, v));
        if impact.is_none() && v.dot(&normal).abs() < 1e-6 && t > 0.1 {
            impact = Some(t);
        }
    }
    let impact = impact.expect("the patch lands");
    // With 30 fps sampling, the first frame after impact ends within 33 ms after 0.2019 s.
    assert!(
        impact > 0.2019 && impact < 0.2019 + frame_dt + 1e-9,
        "impact seen at {impact} s, expected just after 0.2019 s"
    );
    let (t_end, v_end) = samples[14];
    let expected = 1.2606 + 6.243 * (t_end - 0.2019);
    let measured = v_end.dot(&downhill);
    assert!(
        (measured - expected).abs() / expected < 0.01,
        "tangential speed {measured:.4} m/s at {t_end:.3} s, expected {expected:.4}"
    );
    let accel = (samples[14].1 - samples[9].1).dot(&downhill) / (5.0 * frame_dt);
    assert!(
        (accel / 6.243 - 1.0).abs() < 0.01,
        "acceleration after impact {accel:.4} m/s^2, expected 6.243"
    );
}
