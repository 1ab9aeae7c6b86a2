//! Scenarios of contact: no vertex inside a sphere after a drape, the residual falling with
//! iterations, and light cloth staying out of a swinging arm (`--long`).

use super::Outcome;
use crate::drape_bench::DrapeBench;
use crate::error::Result;
use sim::SceneConfig;
use sim::obstacles::{Obstacles, Sphere};
use sim::scene::Scene;
use sim::{ClothMesh, ClothState, Vec3};
use sim::{ClothSetup, Solver};
use sim::{Material, SolverParams};

/// Sphere drape: no vertex inside the sphere (the drape bench at 32 x 32, 64 x 64 with --long).
pub(super) fn sphere_drape(long: bool) -> Result<Vec<Outcome>> {
    let r = DrapeBench::new(if long { 64 } else { 32 }).run()?;
    Ok(vec![
        Outcome::new(
            "sphere_drape_vertices_inside",
            0.0,
            r.measures.verts_inside_sphere as f64,
            0.0,
            "vertices",
        ),
        Outcome::new(
            "sphere_drape_max_edge_stretch",
            1.0,
            r.measures.max_edge_stretch,
            0.035,
            "1",
        ),
    ])
}

/// The residual falls with iterations (one contact-rich step of the drape scene). Not
/// strictly at every count: measured 0.050, 0.0085, 0.0103, 0.0091, 0.0023 m/s at 2, 5, 7,
/// 10, 40 iterations (contacts switching between stick and slide make a small bump).
pub(super) fn convergence(_long: bool) -> Result<Vec<Outcome>> {
    let mut residuals = Vec::new();
    for iterations in [2, 10, 40] {
        let mut bench = DrapeBench::new(16);
        bench.params.max_iterations = iterations;
        bench.params.tolerance = 0.0;
        let mesh = ClothMesh::grid(16, 1.0, 0.505)?;
        let mut solver = Solver::new(
            ClothSetup::new(mesh.clone(), DrapeBench::material()),
            bench.params,
            1.0 / 30.0,
        )?;
        let sphere = Sphere::new(Vec3::new(0.0, 0.2, 0.0), 0.3, 0.3);
        let mut obstacles = Obstacles::props(vec![Box::new(sphere)]);
        let mut state = ClothState::at_rest(mesh.rest().to_vec());
        state.velocities.iter_mut().for_each(|v| v.y = -1.0);
        let report = solver.step(&mut state, &mut obstacles, 8, 1.0 / 240.0)?;
        residuals.push(report.residual);
    }
    let monotone = residuals.windows(2).all(|w| w[1] <= w[0]);
    let ratio = residuals[2] / residuals[0];
    Ok(vec![
        Outcome::new(
            "convergence_residual_monotone",
            1.0,
            monotone as u8 as f64,
            0.0,
            "1 = residual falls at 2, 10, 40 iterations",
        ),
        Outcome::new("convergence_residual_ratio_40_vs_2", 0.0, ratio, 0.5, "1"),
    ])
}

/// The soft-cloth run (issue 40; docs/BENCHMARKS.md, the soft-cloth blow-up), `--long`
/// only: shard 0/20's train-run-s2d2 of `specs/paper.toml` (the library's long-sleeved midi
/// dress at 0.054 kg/m^2 and k_s 115 N/m on `run:amplitude=0.7`) at 32 iterations, 110
/// frames. Without the per-frame penetration check the swinging arm leaves the sleeve inside
/// at frame 107 (40.1 mm, stretch 2.93); with it that frame is run again at 8 substeps
/// (7.0 mm and 1.36 over the whole run).
pub(super) fn soft_cloth(long: bool) -> Result<Vec<Outcome>> {
    if !long {
        return Ok(Vec::new());
    }
    const BETAS: [f64; 10] = [
        -0.29738495720997093,
        0.7263261491889246,
        0.892864385178409,
        -0.41799733074102496,
        0.38145990972883803,
        0.49348813706911887,
        0.7572639342599112,
        -0.703554805933325,
        -0.41975755465997056,
        0.6923110901957812,
    ];
    let model = motions::BodyModel::default_body();
    let (garment, attachments) = sim::sources::garment(
        "dress_longsleeve_midi",
        &model,
        &sim::templates::cache_dir(),
        |_| {},
    )?;
    let shaped = model.shape(&BETAS)?;
    let motion = sim::sources::motion("run:speed=1.0,amplitude=0.7", &model, &shaped)?;
    let config = SceneConfig {
        garment: "dress_longsleeve_midi".into(),
        motion: motion.name.clone(),
        betas: BETAS.to_vec(),
        frames: Some(110),
        blend_frames: 20,
        settle_frames: 10,
        material: Material {
            stretch: 114.55984705217656,
            density: 0.05379129783082185,
            bending: 2.1721538652438552e-8,
        },
        solver: SolverParams {
            max_iterations: 32,
            ..sim::config::garment_solver()
        },
        ..SceneConfig::default()
    };
    let template = (garment.positions, garment.triangles);
    let scene = Scene::new(config.validated()?, template, attachments, motion, &model)?;
    let run = scene.run(&model, |_| Ok(()))?;
    Ok(vec![
        Outcome::new(
            "soft_cloth_max_penetration_mm",
            0.0,
            run.max_penetration_m * 1e3,
            10.0,
            "mm",
        ),
        Outcome::new(
            "soft_cloth_max_edge_stretch",
            1.0,
            run.max_edge_stretch,
            0.5,
            "1",
        ),
    ])
}
