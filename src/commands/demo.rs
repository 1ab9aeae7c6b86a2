//! `dit-garment demo`: the main job on built-in defaults. The default garment (a skirt fitted
//! and draped on the default body) rides the default body through the built-in `walk` motion
//! (blend-in from the canonical A-pose and settle frames included); the sequence is written as
//! MCAP, every K-th frame as OBJ (garment and body), pictures (a contact sheet of six frames
//! and a GIF of the whole sequence), the HTML viewer, and a JSON summary.

use anyhow::{Context, Result};
use render::View;
use serde_json::json;

use crate::cli::DemoArgs;
use crate::output::write_json;
use crate::pictures::{RenderJob, render_recording, write_view};
use crate::run::{RecordOptions, prepare, print_config, record, resolve_config, summary_json};

pub fn run(args: &DemoArgs) -> Result<()> {
    let config = resolve_config(&args.scene)?;
    if print_config(&args.scene, &config)? {
        return Ok(());
    }
    let out = args.out.as_deref().context("demo needs --out DIR")?;
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
    let rendered = render_recording(&sequence, &prepared.model, true, &job, &pictures)?;
    let viewer = out.join("view.html");
    write_view(
        std::slice::from_ref(&sequence),
        &prepared.model,
        true,
        1,
        &viewer,
    )?;
    let mut summary = summary_json(&s, &sequence);
    summary["contact_sheet"] = json!(rendered.sheet);
    summary["gif"] = json!(rendered.gif);
    summary["viewer"] = json!(viewer);
    summary["garment"] = prepared.garment.name.clone().into();
    summary["motion"] = prepared.scene.motion.name.clone().into();
    summary["blend_frames"] = prepared.scene.config.blend_frames.into();
    summary["settle_frames"] = prepared.scene.config.settle_frames.into();
    summary["body_vertices"] = prepared.model.num_vertices().into();
    write_json(&out.join("summary.json"), &summary)?;
    if let Some(path) = &args.json {
        write_json(path, &summary)?;
    }
    println!(
        "demo: '{}' ({} vertices) on the default body ({} vertices) through '{}': {} frames at 30 fps ({} blend-in + {} settle)",
        prepared.garment.name,
        s.vertices,
        prepared.model.num_vertices(),
        prepared.scene.motion.name,
        s.frames,
        prepared.scene.config.blend_frames,
        prepared.scene.config.settle_frames
    );
    println!(
        "  simulated at {:.1} frames/s; max penetration {:.1} mm, max edge stretch {:.3}; wrote {}, OBJ frames in {}, summary.json",
        s.frames_per_s,
        s.max_penetration_m * 1e3,
        s.max_edge_stretch,
        sequence.display(),
        frames_dir.display()
    );
    println!(
        "  pictures: {} and {}; viewer: {} (open it in a browser)",
        rendered.sheet.display(),
        rendered
            .gif
            .as_ref()
            .map_or(String::new(), |g| g.display().to_string()),
        viewer.display()
    );
    Ok(())
}
