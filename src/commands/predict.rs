//! `dit-garment predict`: a garment posed directly by a trained surrogate through a motion,
//! recorded as MCAP through the engine's recording writer (with the model and sampler
//! settings in its metadata), with a progress bar and a JSON summary.

use std::time::Instant;

use anyhow::{Context, Result, bail};
use serde_json::json;
use surrogate::burn::prelude::Device;
use surrogate::predict::{Noise, Settings};
use surrogate::run::TrainedModel;

use crate::cli::PredictArgs;
use files::write_json;
use surrogate::predict::{SceneInput, SceneRequest, predict_scene};

use crate::run::frames_bar;
use crate::run::{prepare, resolve_inputs, set_threads};

pub fn run(args: &PredictArgs) -> Result<()> {
    let started = Instant::now();
    set_threads(args.threads)?;
    if args.out.is_dir() {
        bail!(
            "--out {}: is a folder (give a .mcap file name)",
            args.out.display()
        );
    }
    let trained = TrainedModel::load_named(&args.model, &Device::flex())?;
    let settings = Settings {
        shift: args.shift,
        noise: if args.per_frame_noise {
            Noise::PerFrame
        } else {
            Noise::Shared
        },
        resolve_penetration: args.resolve_penetration,
        inside_test: true,
        ..args.sampler.settings(Settings::for_model(&trained))
    };
    settings.validate().context("bad sampler settings")?;
    let config = resolve_inputs(&args.scene)?;
    let prepared = prepare(config)?;
    let model_name = trained.run.display().to_string();
    let software = format!("dit-garment {} predict", env!("CARGO_PKG_VERSION"));
    let prepared_s = started.elapsed().as_secs_f64();
    let request = SceneRequest {
        trained: &trained,
        model_name: &model_name,
        settings: &settings,
        out: &args.out,
        obj_dir: args.obj_dir.as_deref(),
        body_vertices: args.body_vertices,
    };
    let bar = frames_bar("predicting", prepared.scene.num_frames(), args.quiet);
    let p = predict_scene(
        &SceneInput::of_scene(&prepared, &software),
        &request,
        &mut || bar.inc(1),
    )?;
    bar.finish_and_clear();
    let (garment, scene, stats) = (&prepared.garment, &prepared.scene, &p.stats);
    let (frames, frames_per_s, seen) = (p.frames, p.frames_per_s, p.seen);
    let (max_penetration, pushed, timing) = (stats.max_penetration_m, stats.pushed, stats.timing);
    let wall_s = started.elapsed().as_secs_f64();
    if let Some(path) = &args.json {
        let threads = rayon::current_num_threads();
        write_json(
            path,
            &json!({
                "frames": frames, "finite": stats.finite, "frames_per_s": frames_per_s,
                "wall_s": wall_s, "steps": settings.steps, "guidance": settings.guidance.weight,
                "guidance_start": settings.guidance.start, "batch": settings.batch,
                "draws": settings.draws,
                "E_c_percent": p.e_c, "E_c_vertex_percent": p.e_c_vertex,
                "frames_scored": stats.collision.len(),
                "max_penetration_m": max_penetration, "max_verts_inside": stats.max_inside,
                "pushed_vertices": pushed, "vertices": p.vertices, "model": model_name,
                "garment": garment.name, "template_seen_in_training": seen,
                "motion": scene.motion.name, "seed": settings.seed,
                "noise": settings.noise, "resolve_penetration": settings.resolve_penetration,
                "threads": threads, "prepare_s": prepared_s + p.garment_s, "timing_s": timing,
                "recording": args.out,
            }),
        )?;
    }
    say!(
        "predict: '{}' ({} vertices{}) through '{}': {} frames in {:.1} s ({:.1} frames/s, {} steps, guidance {})",
        garment.name,
        p.vertices,
        if seen {
            ", seen in training"
        } else {
            ", unseen in training"
        },
        scene.motion.name,
        frames,
        timing.wall_s,
        frames_per_s,
        settings.steps,
        settings.guidance.weight,
    );
    say!(
        "  E_c {:.2}% of surface samples inside the body, max penetration {:.1} mm{}; wrote {}",
        p.e_c,
        max_penetration.unwrap_or(f64::NAN) * 1e3,
        if settings.resolve_penetration {
            format!(", {pushed} vertices pushed out after sampling")
        } else {
            String::new()
        },
        args.out.display()
    );
    Ok(())
}
