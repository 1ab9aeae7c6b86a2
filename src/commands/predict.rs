//! `dit-garment predict`: a garment posed directly by a trained surrogate through a motion,
//! recorded as MCAP through the engine's recording writer (with the model and sampler
//! settings in its metadata), with a progress bar and a JSON summary.

use std::time::Instant;

use anyhow::{Context, Result, bail};
use indicatif::{ProgressBar, ProgressDrawTarget, ProgressStyle};
use serde_json::json;
use sim::recording::TemplateArrays;
use surrogate::burn::prelude::Device;
use surrogate::predict::{BodySequence, Guidance, Noise, Predictor, Settings};
use surrogate::train::TrainedModel;

use crate::cli::{ModelArgs, PredictArgs, SceneArgs};
use crate::output::write_json;
use crate::prediction::{PredictionStats, Recorded, model_dir, record_prediction};
use crate::run::{prepare, resolve_config, set_threads};

pub fn run(args: &PredictArgs) -> Result<()> {
    let started = Instant::now();
    set_threads(args.threads)?;
    let settings = Settings {
        steps: args.steps,
        shift: args.shift,
        guidance: Guidance {
            weight: args.guidance,
            start: args.guidance_start,
            ..Guidance::default()
        },
        seed: args.seed,
        batch: args.batch,
        noise: if args.per_frame_noise {
            Noise::PerFrame
        } else {
            Noise::Shared
        },
        resolve_penetration: args.resolve_penetration,
    };
    if let Err(e) = settings.validate() {
        bail!("bad sampler settings: {e}");
    }
    if args.out.is_dir() {
        bail!(
            "--out {}: is a folder (give a .mcap file name)",
            args.out.display()
        );
    }
    let run_dir = model_dir(&args.model)?;
    let trained = TrainedModel::load(&run_dir, &Device::flex())
        .with_context(|| format!("loading the model in {}", run_dir.display()))?;

    let scene_args = SceneArgs {
        config: None,
        config_from: args.config_from.clone(),
        print_config: false,
        garment: args.garment.clone(),
        motion: args.motion.clone(),
        model: ModelArgs {
            model: args.body_model.clone(),
        },
        betas: args.betas.clone(),
        material: args.material.clone(),
        friction: None,
        frames: args.frames,
        blend_frames: args.blend_frames,
        settle_frames: args.settle_frames,
        substeps: None,
        iterations: None,
        no_self_contact: false,
        self_contact_distance: None,
        self_friction: None,
    };
    let config = resolve_config(&scene_args)?;
    let prepared = prepare(config)?;
    let (model, garment, scene) = (&prepared.model, &prepared.garment, &prepared.scene);
    let predictor = Predictor::new(&trained, model)?;
    let template = TemplateArrays {
        positions: garment.positions.clone(),
        triangles: garment.triangles.clone(),
        uvs: garment.uvs.clone(),
        uv_triangles: garment.uv_triangles.clone(),
    };
    let mut ready = predictor
        .garment(&template)
        .with_context(|| format!("garment '{}'", garment.name))?;
    let motion = scene.body_motion();
    let frames = scene.num_frames();
    let betas: Vec<Vec<f64>> = (0..frames).map(|k| scene.frame_betas(k)).collect();
    let body = BodySequence {
        motion: &motion,
        betas: &betas,
        material: scene.config.material,
    };
    let seen = trained
        .data
        .templates
        .iter()
        .any(|t| t.name == garment.name);
    let model_name = run_dir.display().to_string();
    let predicted = json!({
        "model": model_name, "target": trained.data.target.name(),
        "resolution": trained.data.resolution, "settings": settings,
        "template_seen_in_training": seen,
    });
    let software = format!("dit-garment {} predict", env!("CARGO_PKG_VERSION"));
    let meta = scene.sequence_meta(&garment.name, model.name(), &software);

    let bar = ProgressBar::new(frames as u64).with_style(
        ProgressStyle::with_template(
            "predicting [{bar:30}] {pos}/{len} frames ({per_sec}, eta {eta})",
        )?
        .progress_chars("=> "),
    );
    if args.quiet {
        bar.set_draw_target(ProgressDrawTarget::hidden());
    }
    let prepared_s = started.elapsed().as_secs_f64();
    let recorded = Recorded {
        predictor: &predictor,
        garment: &mut ready,
        template: &template,
        body,
        frames: 0..frames,
        settings: &settings,
        meta: &meta,
        predicted: &predicted,
        faces: model.faces(),
        body_vertices: args.body_vertices,
        obj: args.obj_dir.as_deref().map(|d| (d, garment.as_ref())),
        bar: &bar,
    };
    let stats = record_prediction(&args.out, recorded)
        .with_context(|| format!("predicting into {}", args.out.display()))?;
    bar.finish_and_clear();
    let PredictionStats {
        finite,
        max_penetration_m: max_penetration,
        max_inside,
        pushed,
        collision,
        timing,
    } = stats;

    let sampling_s = timing.wall_s;
    let frames_per_s = frames as f64 / sampling_s.max(1e-9);
    let mean = |f: fn(&(f64, f64)) -> f64| -> f64 {
        collision.iter().map(f).sum::<f64>() / collision.len().max(1) as f64
    };
    let (e_c, e_c_vertex) = (mean(|c| c.0), mean(|c| c.1));
    let wall_s = started.elapsed().as_secs_f64();
    if let Some(path) = &args.json {
        let threads = rayon::current_num_threads();
        write_json(
            path,
            &json!({
                "frames": frames, "finite": finite, "frames_per_s": frames_per_s,
                "wall_s": wall_s, "steps": settings.steps, "guidance": settings.guidance.weight,
                "guidance_start": settings.guidance.start, "batch": settings.batch,
                "E_c_percent": e_c, "E_c_vertex_percent": e_c_vertex,
                "frames_scored": collision.len(),
                "max_penetration_m": max_penetration, "max_verts_inside": max_inside,
                "pushed_vertices": pushed, "vertices": ready.vertices(), "model": model_name,
                "garment": garment.name, "template_seen_in_training": seen,
                "motion": scene.motion.name, "seed": settings.seed,
                "noise": settings.noise, "resolve_penetration": settings.resolve_penetration,
                "threads": threads, "prepare_s": prepared_s, "timing_s": timing,
                "recording": args.out,
            }),
        )?;
    }
    println!(
        "predict: '{}' ({} vertices{}) through '{}': {} frames in {:.1} s ({:.1} frames/s, {} steps, guidance {})",
        garment.name,
        ready.vertices(),
        if seen {
            ", seen in training"
        } else {
            ", unseen in training"
        },
        scene.motion.name,
        frames,
        sampling_s,
        frames_per_s,
        settings.steps,
        settings.guidance.weight,
    );
    println!(
        "  E_c {:.2}% of surface samples inside the body, max penetration {:.1} mm{}; wrote {}",
        e_c,
        max_penetration * 1e3,
        if settings.resolve_penetration {
            format!(", {pushed} vertices pushed out after sampling")
        } else {
            String::new()
        },
        args.out.display()
    );
    Ok(())
}
