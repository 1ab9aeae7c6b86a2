//! Bad scene settings get clear errors before anything runs: NaN in a motion, negative
//! friction, zero density, bad solver counts, and a body mesh that does not close.

use motions::library::MotionSpec;
use motions::{BodyModel, Motion};
use sim::obstacles::AnimatedMesh;
use sim::scene::Scene;
use sim::{ClothMesh, SceneConfig, SolverParams, Vec3};

fn config() -> SceneConfig {
    SceneConfig {
        blend_frames: 2,
        settle_frames: 1,
        frames: Some(2),
        solver: SolverParams::default(),
        ..SceneConfig::default()
    }
}

fn motion(model: &BodyModel) -> Motion {
    let shaped = model.shape(&[]).unwrap();
    MotionSpec::parse("walk:duration=0.2")
        .unwrap()
        .generate(model, &shaped)
        .unwrap()
}

fn scene(config: SceneConfig, motion: Motion, model: &BodyModel) -> sim::Result<Scene> {
    let grid = ClothMesh::grid(3, 0.1, 0.0).unwrap();
    let template = grid
        .rest()
        .iter()
        .map(|p| [p.x, p.y + 0.5, p.z + 0.5])
        .collect();
    Scene::new(
        config.validated()?,
        (template, grid.triangles().to_vec()),
        vec![],
        motion,
        model,
    )
}

fn error_of(config: SceneConfig, motion: Motion, model: &BodyModel) -> String {
    scene(config, motion, model)
        .expect_err("the scene is rejected")
        .to_string()
}

#[test]
fn bad_settings_are_named() {
    let model = BodyModel::default_body();
    let good = scene(config(), motion(&model), &model).unwrap();
    good.run(&model, |_| Ok(())).unwrap();

    let mut m = motion(&model);
    m.frames[1].pose[5] = f64::NAN;
    let message = error_of(config(), m, &model);
    assert!(message.contains("frame 1 has a non-finite"), "{message}");

    let mut c = config();
    c.friction = -0.1;
    let message = error_of(c, motion(&model), &model);
    assert!(message.starts_with("friction = -0.1"), "{message}");

    let mut c = config();
    c.material.density = 0.0;
    let message = error_of(c, motion(&model), &model);
    assert!(
        message.starts_with("material.rho_kg_per_m2 = 0"),
        "{message}"
    );

    let mut c = config();
    c.solver.substeps = 0;
    let message = error_of(c, motion(&model), &model);
    assert!(message.starts_with("solver.substeps = 0"), "{message}");

    let mut c = config();
    c.betas = vec![f64::INFINITY];
    let message = error_of(c, motion(&model), &model);
    assert!(message.starts_with("betas[0] = inf"), "{message}");
}

#[test]
fn an_open_body_is_refused() {
    let v: Vec<Vec3> = (0..8)
        .map(|i| Vec3::new((i & 1) as f64, ((i >> 1) & 1) as f64, ((i >> 2) & 1) as f64))
        .collect();
    let faces = vec![
        [0, 2, 1],
        [1, 2, 3],
        [4, 5, 6],
        [5, 7, 6],
        [0, 1, 4],
        [1, 5, 4],
        [2, 6, 3],
        [3, 6, 7],
        [0, 4, 2],
        [2, 4, 6],
        [1, 3, 5],
    ];
    let error = AnimatedMesh::new(&v, &faces, 0.3)
        .err()
        .expect("open body refused")
        .to_string();
    assert!(error.contains("not closed"), "{error}");
}
