//! The golden sequences: short garment-on-moving-body recordings checked in under
//! `regress/goldens/`, re-simulated and compared with the metrics; `bless` regenerates them.

use super::Outcome;
use crate::error::{Error, Result};
use sim::SceneConfig;
use sim::recording::{Channels, SequenceWriter, TemplateArrays};
use sim::scene::{FPS, Scene};
use sim::{Material, SolverParams};

/// Golden sequences: short garment-on-moving-body recordings checked in under `regress/goldens/`,
/// re-simulated and compared with the metrics, so any unintended change to the engine fails.
pub struct Golden {
    /// File stem under `regress/goldens/`.
    pub name: &'static str,
    /// Motion (built-in with parameters).
    pub motion: &'static str,
    /// Body shape.
    pub betas: &'static [f64],
}

/// The golden sequences.
pub const GOLDENS: [Golden; 2] = [
    Golden {
        name: "skirt_walk",
        motion: "walk:duration=0.5",
        betas: &[],
    },
    Golden {
        name: "skirt_jumping_jacks",
        motion: "jumping_jacks:duration=0.5",
        betas: &[1.0, 0.5],
    },
];

/// Largest mean vertex distance (cm) a re-simulation may show against its golden: the engine
/// is deterministic, so this only absorbs floating-point differences between machines.
pub const GOLDEN_TOLERANCE_CM: f64 = 0.01;

/// Where the golden files live.
pub fn golden_dir() -> std::path::PathBuf {
    std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("goldens")
}

/// The golden's scene: a coarse built-in skirt (48 x 16 vertices) on the default body, blend-in
/// 6 + settle 2 frames, then the motion. `stretch_scale` perturbs k_s (tests).
pub fn golden_scene(
    g: &Golden,
    stretch_scale: f64,
) -> Result<(Scene, garments::Garment, motions::BodyModel)> {
    let model = motions::BodyModel::default_body();
    let params = garments::SkirtParams {
        columns: 48,
        rings: 16,
        ..garments::SkirtParams::default()
    };
    let (garment, attachments) = sim::scene::builtin_template(&model, "skirt", &params)?;
    let shaped = model.shape(g.betas)?;
    let motion = motions::library::MotionSpec::parse(g.motion)?.generate(&model, &shaped)?;
    let config = SceneConfig {
        // Not a garment name the command line knows: the golden template is a coarse skirt.
        garment: "golden skirt (48 x 16)".into(),
        motion: g.motion.into(),
        betas: g.betas.to_vec(),
        friction: 0.3,
        blend_frames: 6,
        settle_frames: 2,
        material: Material {
            stretch: Material::default().stretch * stretch_scale,
            ..Material::default()
        },
        solver: SolverParams {
            substeps: 2,
            max_iterations: 8,
            ..SolverParams::default()
        },
        ..SceneConfig::default()
    };
    let template = (garment.positions.clone(), garment.triangles.clone());
    let scene = Scene::new(config.validated()?, template, attachments, motion, &model)?;
    Ok((scene, garment, model))
}

/// Simulates a golden's scene, returning the garment frames.
pub fn simulate_golden(g: &Golden, stretch_scale: f64) -> Result<Vec<Vec<[f64; 3]>>> {
    let (scene, _, model) = golden_scene(g, stretch_scale)?;
    let mut frames = Vec::new();
    scene.run(&model, |f| {
        frames.push(f.garment.to_vec());
        Ok(())
    })?;
    Ok(frames)
}

/// Mean E_v (cm) over every 5th frame of `frames` against the golden file, and the frame count.
pub fn golden_distance(g: &Golden, frames: &[Vec<[f64; 3]>]) -> Result<f64> {
    let path = golden_dir().join(format!("{}.mcap", g.name));
    let golden = sim::recording::Recording::read(&path)?;
    if golden.garment.len() != frames.len() || golden.template.positions.len() != frames[0].len() {
        return Err(Error::Golden {
            path: path.display().to_string(),
            message: format!(
                "golden has {} frames of {} vertices, the re-simulation {} of {}",
                golden.garment.len(),
                golden.template.positions.len(),
                frames.len(),
                frames[0].len()
            ),
        });
    }
    let scorer =
        sim::metrics::Scorer::new(&golden.template.positions, &golden.template.triangles, 0)
            .with_samples(2000);
    let scores: Vec<sim::metrics::Scores> = (0..frames.len())
        .step_by(sim::metrics::FRAME_STRIDE)
        .map(|k| {
            let gt: Vec<[f64; 3]> = golden.garment[k]
                .iter()
                .map(|p| p.map(|c| c as f64))
                .collect();
            scorer.frame(&frames[k], &gt, None, k)
        })
        .collect();
    Ok(sim::metrics::Scores::mean(&scores).E_v)
}

pub(super) fn goldens(_long: bool) -> Result<Vec<Outcome>> {
    GOLDENS
        .iter()
        .map(|g| {
            let frames = simulate_golden(g, 1.0)?;
            let d = golden_distance(g, &frames)?;
            Ok(Outcome::new(
                &format!("golden_{}_E_v", g.name),
                0.0,
                d,
                GOLDEN_TOLERANCE_CM,
                "cm",
            ))
        })
        .collect()
}

/// Regenerates the golden files and records why in `regress/goldens/BLESSED.md`.
pub fn bless(reason: &str) -> Result<Vec<std::path::PathBuf>> {
    let io = |path: &std::path::Path, e: std::io::Error| Error::Golden {
        path: path.display().to_string(),
        message: e.to_string(),
    };
    let dir = golden_dir();
    std::fs::create_dir_all(&dir).map_err(|e| io(&dir, e))?;
    let mut written = Vec::new();
    for g in &GOLDENS {
        let (scene, garment, model) = golden_scene(g, 1.0)?;
        let path = dir.join(format!("{}.mcap", g.name));
        let (tmp, file) = files::Temporary::create(&path)?;
        let software = format!("sim {}", env!("CARGO_PKG_VERSION"));
        let garment_name = format!("{} (48 x 16)", garment.name);
        let meta = scene.sequence_meta(&garment_name, model.name(), &software);
        let template = TemplateArrays::from(&garment);
        let channels = Channels {
            template: Some(&template),
            stats: true,
            ..Channels::default()
        };
        let out = std::io::BufWriter::new(file);
        let mut writer = SequenceWriter::new(out, &meta, channels, FPS)?;
        scene.run(&model, |f| writer.write_frame(&f.record()))?;
        writer.finish()?;
        tmp.persist()?;
        written.push(path);
    }
    let log = dir.join("BLESSED.md");
    let mut text = std::fs::read_to_string(&log)
        .unwrap_or_else(|_| "# Golden sequences: why they were regenerated\n\n".into());
    let stamp = std::time::SystemTime::now()
        .duration_since(std::time::UNIX_EPOCH)
        .map(|d| d.as_secs())
        .unwrap_or(0);
    text.push_str(&format!(
        "- unix time {stamp}, sim {}: {}\n",
        env!("CARGO_PKG_VERSION"),
        reason.trim()
    ));
    std::fs::write(&log, text).map_err(|e| io(&log, e))?;
    Ok(written)
}
