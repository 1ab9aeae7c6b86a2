//! Bad scene settings get clear errors before anything runs: NaN in a motion, negative
//! friction, zero density, bad solver counts, and a body mesh that does not close.

use motions::library::MotionSpec;
use motions::{BlendIn, BodyModel};
use sim::obstacles::AnimatedMesh;
use sim::scene::Scene;
use sim::{ClothMesh, Material, SolverParams, Vec3};

fn scene(model: &BodyModel) -> Scene {
    let shaped = model.shape(&[]).unwrap();
    let grid = ClothMesh::grid(3, 0.1, 0.0).unwrap();
    Scene {
        template: grid
            .rest()
            .iter()
            .map(|p| [p.x, p.y + 0.5, p.z + 0.5])
            .collect(),
        triangles: grid.triangles().to_vec(),
        betas: vec![],
        motion: MotionSpec::parse("walk:duration=0.2")
            .unwrap()
            .generate(model, &shaped)
            .unwrap(),
        blend: BlendIn {
            blend_frames: 2,
            settle_frames: 1,
        },
        material: Material::default(),
        friction: 0.3,
        params: SolverParams::default(),
        frames: Some(2),
        attachments: vec![],
    }
}

fn error_of(s: &Scene, model: &BodyModel) -> String {
    s.run(model, |_| Ok(()))
        .expect_err("the scene is rejected")
        .to_string()
}

#[test]
fn bad_settings_are_named() {
    let model = BodyModel::default_body();
    let good = scene(&model);
    good.run(&model, |_| Ok(())).unwrap();

    let mut s = good.clone();
    s.motion.frames[1].pose[5] = f64::NAN;
    assert!(
        error_of(&s, &model).contains("non-finite"),
        "{}",
        error_of(&s, &model)
    );

    let mut s = good.clone();
    s.friction = -0.1;
    assert!(error_of(&s, &model).contains("friction"));

    let mut s = good.clone();
    s.material.density = 0.0;
    assert!(error_of(&s, &model).contains("rho"));

    let mut s = good.clone();
    s.params.substeps = 0;
    assert!(error_of(&s, &model).contains("substeps"));

    let mut s = good;
    s.betas = vec![f64::INFINITY];
    assert!(error_of(&s, &model).contains("beta"));
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
