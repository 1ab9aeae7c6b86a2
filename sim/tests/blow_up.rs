//! Blow-up safety: a frame that keeps exploding is retried with smaller steps, then reported.
//! (Determinism is the regression suite's `determinism` scenario.)

use sim::{ClothMesh, ClothSetup, ClothState, Material, Solver, SolverParams};

/// A frame that keeps exploding is retried with smaller steps a bounded number of times, then
/// the run fails with the reason, and the state is left as it was before the frame.
#[test]
fn blow_up_is_retried_then_reported() {
    let mesh = ClothMesh::grid(6, 0.5, 1.0).unwrap();
    // Any falling vertex exceeds this "explosion" speed within the first frame.
    let params = SolverParams {
        max_speed: 0.01,
        max_retries: 2,
        ..SolverParams::default()
    };
    let mut solver = Solver::new(
        ClothSetup::new(mesh.clone(), Material::default()),
        params,
        1.0 / 30.0,
    )
    .unwrap();
    let mut state = ClothState::at_rest(mesh.rest().to_vec());
    let before = state.clone();
    let error = solver
        .advance_frame(
            &mut state,
            &mut sim::obstacles::Obstacles::default(),
            0.0,
            7,
        )
        .unwrap_err()
        .to_string();
    assert!(
        error.contains("frame 7") && error.contains("2 retries") && error.contains("m/s"),
        "{error}"
    );
    assert_eq!(state, before);
}
