//! `dit-garment demo`: the main job on built-in defaults. A held-out library t-shirt
//! (`vneck_tee`, draped on the default body) rides the default body through the built-in `walk` motion
//! (blend-in from the canonical A-pose and settle frames included) in the engine; the shipped
//! surrogate then predicts the same sequence (same body poses, shapes and material), and the
//! two are compared with the paper's metrics. Written: both recordings as MCAP, every K-th
//! simulated frame as OBJ, pictures (the simulation's contact sheet and GIF, a simulated |
//! predicted | error sheet and GIF), one viewer page playing both, and a JSON summary.

use anyhow::{Context, Result};
use render::View;
use serde_json::{Value, json};
use sim::run::Prepared;
use surrogate::burn::prelude::Device;
use surrogate::predict::Settings;
use surrogate::run::TrainedModel;

use crate::cli::DemoArgs;
use files::write_json;
use render::recording::{
    RenderJob, comparison_gif, comparison_sheet, render_recording, write_view,
};
use surrogate::predict::{SceneRequest, predict_scene};

use crate::run::{RecordOptions, prepare, print_config, record, resolve_config, summary_json};
use crate::run::{frames_bar, gif_progress};

/// The demo's garment: a library design the shipped model was not trained on (held out in
/// specs/shipped.toml), of a family it was trained on (t-shirts), so the demo shows the
/// generalization users read the model for.
pub const DEMO_GARMENT: &str = "vneck_tee";

pub fn run(args: &DemoArgs) -> Result<()> {
    let mut config = resolve_config(&args.scene)?;
    let scene = &args.scene;
    if scene.inputs.garment.is_none()
        && scene.config.is_none()
        && scene.inputs.config_from.is_none()
    {
        config.garment = DEMO_GARMENT.to_string();
    }
    if print_config(&args.scene, &config)? {
        return Ok(());
    }
    let out = args.out.as_deref().context("demo needs --out DIR")?;
    // The model is loaded before the simulation so that a missing or damaged one stops the
    // demo before minutes of work.
    let surrogate = match args.surrogate.as_str() {
        "none" => None,
        name => {
            let trained = TrainedModel::load_named(name, &Device::flex())?;
            Some((name.to_string(), trained))
        }
    };
    let prepared = prepare(config)?;
    std::fs::create_dir_all(out).with_context(|| format!("cannot create {}", out.display()))?;
    let sequence = out.join("sequence.mcap");
    let frames_dir = out.join("frames");
    let obj = (args.obj_every > 0).then_some((frames_dir.as_path(), args.obj_every));
    let options = RecordOptions {
        obj,
        ..RecordOptions::default()
    };
    let s = record(&prepared, &sequence, options)?;
    let job = RenderJob {
        frames: &[],
        views: &[View::ThreeQuarter],
        size: 512,
        ssaa: 2,
        colour_by: None,
        gif: Some((2, 320)),
    };
    let pictures = out.join("pictures");
    let mut progress = gif_progress();
    let rendered = render_recording(
        &sequence,
        &prepared.model,
        true,
        &job,
        &pictures,
        &mut progress,
    )?;
    let mut summary = summary_json(&s, &sequence);
    let mut recordings = vec![sequence.clone()];
    if let Some((name, trained)) = &surrogate {
        let p = predict_and_compare(&prepared, name, trained, out, &pictures)?;
        recordings.push(out.join("predicted.mcap"));
        summary["speedup"] = json!(s.wall_s / p["wall_s"].as_f64().unwrap_or(f64::NAN));
        summary["comparison_sheet"] = p["comparison_sheet"].clone();
        summary["comparison_gif"] = p["comparison_gif"].clone();
        summary["predicted"] = p;
    }
    let viewer = out.join("view.html");
    write_view(&recordings, &prepared.model, true, 1, &viewer)?;
    summary["contact_sheet"] = json!(rendered.sheet);
    summary["gif"] = json!(rendered.gif);
    summary["viewer"] = json!(viewer);
    summary["garment"] = prepared.garment.name.clone().into();
    summary["motion"] = prepared.scene.motion.name.clone().into();
    summary["blend_frames"] = prepared.scene.config.blend_frames.into();
    summary["settle_frames"] = prepared.scene.config.settle_frames.into();
    summary["body_vertices"] = prepared.model.num_vertices().into();
    print_summary(&prepared, &s, &summary)?;
    write_json(&out.join("summary.json"), &summary)?;
    if let Some(path) = &args.json {
        write_json(path, &summary)?;
    }
    Ok(())
}

/// Predicts the simulated scene with `trained` into `OUT/predicted.mcap`, scores it against
/// the simulation and draws the comparison; returns the summary's `predicted` object.
fn predict_and_compare(
    prepared: &Prepared,
    name: &str,
    trained: &TrainedModel,
    out: &std::path::Path,
    pictures: &std::path::Path,
) -> Result<Value> {
    // The engine's frames/s is the bar here: no inside test after sampling (E_c is scored
    // from the recording afterwards).
    let settings = Settings {
        inside_test: false,
        ..Settings::for_model(trained)
    };
    let path = out.join("predicted.mcap");
    let software = format!("dit-garment {} demo", env!("CARGO_PKG_VERSION"));
    let request = SceneRequest {
        trained,
        model_name: name,
        settings: &settings,
        out: &path,
        obj_dir: None,
        body_vertices: false,
    };
    let bar = frames_bar("predicting", prepared.scene.num_frames(), false);
    let p = predict_scene(
        &surrogate::predict::SceneInput::of_scene(prepared, &software),
        &request,
        &mut || bar.inc(1),
    )?;
    bar.finish_and_clear();
    let truth = out.join("sequence.mcap");
    let scores = sim::metrics::compare_recordings(&truth, &path, &prepared.model, 0)?;
    let n = p.frames;
    let frames: Vec<usize> = (0..6).map(|i| i * (n - 1) / 5).collect();
    let sheet = pictures.join("comparison_sheet.png");
    comparison_sheet(&truth, &path, &prepared.model, &frames, 320, &sheet)?;
    let gif = pictures.join("comparison.gif");
    comparison_gif(&truth, &path, &prepared.model, 2, 240, &gif)?;
    let m = &scores.mean;
    Ok(json!({
        "recording": path, "frames": n, "frames_per_s": p.frames_per_s,
        "wall_s": p.stats.timing.wall_s, "prepare_s": p.garment_s,
        "E_v": m.E_v, "E_CD": m.E_CD, "E_CD_cm": m.E_CD_cm, "E_n": m.E_n, "E_c": m.E_c,
        "E_c_vertex": m.E_c_vertex, "E_b": m.E_b, "E_s": m.E_s, "E_d": m.E_d,
        "frames_scored": scores.per_frame.len(), "jitter": scores.jitter_b,
        "max_penetration_m": p.stats.max_penetration_m, "max_verts_inside": p.stats.max_inside,
        "finite": p.stats.finite, "model": name, "steps": settings.steps,
        "guidance": settings.guidance.weight, "seed": settings.seed,
        "template_seen_in_training": p.seen,
        "comparison_sheet": sheet, "comparison_gif": gif,
    }))
}

/// The short table the demo prints.
fn print_summary(prepared: &Prepared, s: &sim::scene::RunSummary, summary: &Value) -> Result<()> {
    let predicted = summary.get("predicted");
    let config = &prepared.scene.config;
    say!(
        "demo: '{}' ({} vertices) on the default body ({} vertices) through '{}': {} frames at 30 fps ({} blend-in + {} settle)",
        prepared.garment.name,
        s.vertices,
        prepared.model.num_vertices(),
        prepared.scene.motion.name,
        s.frames,
        config.blend_frames,
        config.settle_frames
    );
    say!(
        "  {:<10} {:>9} {:>8} {:>7} {:>7} {:>9}",
        "",
        "frames/s",
        "wall s",
        "E_v cm",
        "E_c %",
        "pen. mm"
    );
    say!(
        "  {:<10} {:>9.1} {:>8.1} {:>7} {:>7} {:>9.1}",
        "simulated",
        s.frames_per_s,
        s.wall_s,
        "-",
        "-",
        s.max_penetration_m * 1e3,
    );
    if let Some(p) = predicted {
        let f = |k: &str| p[k].as_f64().unwrap_or(f64::NAN);
        let depth = p["max_penetration_m"]
            .as_f64()
            .map_or("-".to_string(), |d| format!("{:.1}", d * 1e3));
        say!(
            "  {:<10} {:>9.1} {:>8.1} {:>7.2} {:>7.2} {:>9}",
            "predicted",
            f("frames_per_s"),
            f("wall_s"),
            f("E_v"),
            f("E_c"),
            depth,
        );
        say!(
            "  the surrogate ({}, {} steps, guidance {}; {} in training) ran at {:.1}x the engine's speed",
            p["model"].as_str().unwrap_or("?"),
            p["steps"],
            p["guidance"],
            if p["template_seen_in_training"] == true {
                "this garment was"
            } else {
                "this garment was not"
            },
            summary["speedup"].as_f64().unwrap_or(f64::NAN)
        );
    }
    let path = |k: &str| summary[k].as_str().unwrap_or("?").to_string();
    say!(
        "  wrote {}{}, OBJ frames, summary.json",
        path("recording"),
        predicted.map_or(String::new(), |p| format!(
            " and {}",
            p["recording"].as_str().unwrap_or("?")
        ))
    );
    say!(
        "  pictures: {} and {}{}; viewer: {} (open it in a browser)",
        path("contact_sheet"),
        path("gif"),
        predicted.map_or(String::new(), |_| format!(
            "; simulated | predicted | error: {} and {}",
            path("comparison_sheet"),
            path("comparison_gif")
        )),
        path("viewer")
    );
    Ok(())
}
