//! Every constraint row sums to zero, so without gravity, contact or damping every global
//! solve conserves linear momentum (relative 1e-12) at any iteration count, and backward
//! Euler never adds energy once the iteration has converged (PHYSICS.md validation 2).

use sim::{
    BendingRest, ClothMesh, ClothSetup, ClothState, Material, Seam, Solver, SolverParams, Vec3,
};

fn scrambled_state(mesh: &ClothMesh) -> ClothState {
    // Deterministic pseudo-random stretch and velocities.
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

#[test]
fn momentum_is_conserved_and_energy_does_not_grow() {
    let mesh = ClothMesh::grid(8, 0.5, 0.0).unwrap();
    let mut setup = ClothSetup::new(
        mesh.clone(),
        Material {
            stretch: 200.0,
            density: 0.3,
            bending: 1e-4,
        },
    );
    setup.bending_rest = BendingRest::Curved;
    setup.seams = vec![Seam {
        a: 0,
        b: 63,
        stiffness: 50.0,
    }];
    for (iterations, seams) in [(1, true), (3, true), (20, true), (1000, false)] {
        // Seams (an opening-scaled projection) conserve momentum but have no energy of their
        // own in this accounting, so the energy check runs without them.
        let mut setup = setup.clone();
        if !seams {
            setup.seams.clear();
        }
        let params = SolverParams {
            substeps: 2,
            max_iterations: iterations,
            tolerance: 0.0,
            gravity: 0.0,
            ..SolverParams::default()
        };
        let mut solver = Solver::new(setup.clone(), params, 1.0 / 30.0).unwrap();
        solver.set_seam_opening(0.5);
        let mut state = scrambled_state(&mesh);
        let momentum = |s: &ClothState, m: &[f64]| -> Vec3 {
            s.velocities.iter().zip(m).map(|(v, m)| v * *m).sum()
        };
        let p0 = momentum(&state, solver.masses());
        let scale: f64 = state
            .velocities
            .iter()
            .zip(solver.masses())
            .map(|(v, m)| v.norm() * m)
            .sum();
        let mut energy = solver.kinetic_energy(&state) + solver.elastic_energy(&state.positions);
        for frame in 0..20 {
            solver
                .advance_frame(&mut state, &mut [], frame as f64 / 30.0, frame)
                .unwrap();
            let drift = (momentum(&state, solver.masses()) - p0).norm() / scale;
            assert!(
                drift < 1e-12,
                "{iterations} iterations, frame {frame}: momentum drift {drift:e} (tolerance 1e-12)"
            );
            let e = solver.kinetic_energy(&state) + solver.elastic_energy(&state.positions);
            if !seams {
                assert!(
                    e <= energy * (1.0 + 1e-6),
                    "frame {frame}: energy grew from {energy} J to {e} J"
                );
            }
            energy = e;
        }
    }
}
