//! A garment worn by a posed body carried back to the canonical body by the engine, as a
//! simulation's blend-in carried it there: the body moves through `bodies` (one vertex set per
//! frame), the cloth follows with gravity, contact, friction and cloth-cloth contact. What a
//! pose does to cloth that skinning does not (sleeves hanging, a hem swinging) is undone by the
//! same physics that did it, where inverting the skinning cannot (docs/GARMENTS.md).

use motions::BodyModel;

use crate::cloth::{ClothMesh, ClothState, Vec3};
use crate::error::{Error, Result};
use crate::obstacles::{AnimatedMesh, Obstacles};
use crate::params::SolverParams;
use crate::scene::FPS;
use crate::sewing::SewingOptions;
use crate::solver::{ClothSetup, Solver};

fn to_vec3(points: &[[f64; 3]]) -> Vec<Vec3> {
    points.iter().map(|p| Vec3::new(p[0], p[1], p[2])).collect()
}

/// Where cloth of rest shape `rest` (over `triangles`) worn at `start` ends when its body moves
/// through `bodies` (vertex sets of `model`'s body, one per frame at 30 fps, the first the body
/// that wears it at `start`).
pub fn unwind(
    model: &BodyModel,
    rest: &[[f64; 3]],
    triangles: &[[u32; 3]],
    start: &[[f64; 3]],
    bodies: &[Vec<[f64; 3]>],
    options: &SewingOptions,
) -> Result<Vec<[f64; 3]>> {
    let first = bodies.first().ok_or_else(|| Error::Obstacle {
        obstacle: "body".into(),
        problem: "no body frames to unwind through".into(),
    })?;
    if start.len() != rest.len() {
        return Err(Error::Obstacle {
            obstacle: "cloth".into(),
            problem: format!(
                "{} start positions for {} vertices",
                start.len(),
                rest.len()
            ),
        });
    }
    let mesh = ClothMesh::new(to_vec3(rest), triangles.to_vec())?;
    let params = SolverParams {
        // As sewing settles: four substeps and 40 iterations keep light cloth in contact.
        substeps: 4,
        max_iterations: 40,
        self_contact: true,
        ..SolverParams::default()
    };
    let mut solver = Solver::new(ClothSetup::new(mesh, options.material), params, 1.0 / FPS)?;
    solver.set_gravity_and_damping(SolverParams::default().gravity, options.settle_damping);
    let body = AnimatedMesh::new(&to_vec3(first), model.faces(), options.friction)?;
    let mut obstacles = Obstacles::body(body);
    let mut state = ClothState::at_rest(to_vec3(rest));
    state.positions = to_vec3(start);
    for (k, pair) in bodies.windows(2).enumerate() {
        let t0 = k as f64 / FPS;
        let body = obstacles.body.as_mut().ok_or_else(|| Error::Obstacle {
            obstacle: "body".into(),
            problem: "missing from the unwinding scene".into(),
        })?;
        body.set_keyframes(&to_vec3(&pair[0]), &to_vec3(&pair[1]), t0, t0 + 1.0 / FPS)?;
        solver.advance_frame(&mut state, &mut obstacles, t0, k)?;
    }
    Ok(state.positions.iter().map(|p| [p.x, p.y, p.z]).collect())
}
