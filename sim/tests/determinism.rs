//! Same inputs and thread count give identical bits.

use sim::obstacles::{Obstacle, Plane, Sphere};
use sim::{ClothMesh, ClothSetup, ClothState, Material, Solver, SolverParams, Vec3};

fn run() -> Vec<Vec3> {
    let mesh = ClothMesh::grid(20, 1.0, 0.6).unwrap();
    let mut solver = Solver::new(
        ClothSetup::new(mesh.clone(), Material::default()),
        SolverParams::default(),
        1.0 / 30.0,
    )
    .unwrap();
    let mut obstacles: Vec<Box<dyn Obstacle>> = vec![
        Box::new(Sphere::new(Vec3::new(0.0, 0.3, 0.0), 0.25, 0.3)),
        Box::new(Plane::ground(0.0, 0.5)),
    ];
    let mut state = ClothState::at_rest(mesh.rest().to_vec());
    for frame in 0..20 {
        solver
            .advance_frame(&mut state, &mut obstacles, frame as f64 / 30.0, frame)
            .unwrap();
    }
    state.positions
}

#[test]
fn two_runs_are_bit_identical() {
    let (a, b) = (run(), run());
    assert!(a.iter().zip(&b).all(|(p, q)| {
        p.iter()
            .zip(q.iter())
            .all(|(x, y)| x.to_bits() == y.to_bits())
    }));
}

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
        .advance_frame(&mut state, &mut [], 0.0, 7)
        .unwrap_err()
        .to_string();
    assert!(
        error.contains("frame 7") && error.contains("2 retries") && error.contains("m/s"),
        "{error}"
    );
    assert_eq!(state, before);
}
