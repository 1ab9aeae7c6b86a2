//! Free fall is exact in backward Euler: v_n = v_0 + n h g, x_n = x_0 + n h v_0 +
//! g h^2 n (n + 1) / 2 (PHYSICS.md validation 1, relative tolerance 1e-10).

use sim::{ClothMesh, ClothSetup, ClothState, Material, Solver, SolverParams, Vec3};

#[test]
fn free_fall_matches_the_discrete_formula() {
    let mesh = ClothMesh::grid(5, 0.5, 1.0).unwrap();
    let params = SolverParams {
        substeps: 10,
        max_iterations: 5,
        ..SolverParams::default()
    };
    let frame_dt = 1.0 / 30.0;
    let mut solver = Solver::new(
        ClothSetup::new(mesh.clone(), Material::default()),
        params,
        frame_dt,
    )
    .unwrap();
    let v0 = Vec3::new(0.3, 1.5, -0.2);
    let mut state = ClothState::at_rest(mesh.rest().to_vec());
    state.velocities.iter_mut().for_each(|v| *v = v0);
    let h = frame_dt / 10.0;
    let g = Vec3::new(0.0, -9.81, 0.0);
    let mut worst: f64 = 0.0;
    for frame in 0..30 {
        solver
            .advance_frame(&mut state, &mut [], frame as f64 * frame_dt, frame)
            .unwrap();
        let n = ((frame + 1) * 10) as f64;
        let v = v0 + n * h * g;
        let dx = n * h * v0 + g * h * h * n * (n + 1.0) / 2.0;
        for (x, (x0, vel)) in state
            .positions
            .iter()
            .zip(mesh.rest().iter().zip(&state.velocities))
        {
            worst = worst.max((x - (x0 + dx)).norm() / dx.norm());
            worst = worst.max((vel - v).norm() / v.norm());
        }
    }
    assert!(
        worst < 1e-10,
        "relative deviation from the exact discrete free fall: {worst:e} (tolerance 1e-10)"
    );
}
