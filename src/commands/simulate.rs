//! `dit-garment simulate`: a garment on a body through a motion, recorded as MCAP (and
//! optionally OBJ frames), with a progress bar and a JSON summary.

use std::io::Write;
use std::path::Path;
use std::sync::Arc;
use std::time::Instant;

use anyhow::{Context, Result};
use indicatif::{ProgressBar, ProgressDrawTarget, ProgressStyle};
use motions::{BlendIn, BodyModel};
use serde_json::json;
use sim::SolverParams;
use sim::recording::{RecordingWriter, SequenceMeta, TemplateArrays};
use sim::scene::{FPS, RunSummary, Scene};

use crate::cli::{SceneArgs, SimulateArgs};
use crate::inputs;
use crate::output::{write_atomic, write_json};

/// A scene from the flags, with its model and template (shared between the sequences of a
/// dataset run).
pub struct Prepared {
    pub model: Arc<BodyModel>,
    pub garment: Arc<garments::Garment>,
    pub scene: Scene,
}

pub fn prepare(args: &SceneArgs) -> Result<Prepared> {
    let model = Arc::new(inputs::body_model(args.model.model.as_deref())?);
    let material = inputs::material(&args.material)?;
    let (garment, attachments) = inputs::garment(&args.garment, &model)?;
    prepare_with(model, Arc::new(garment), attachments, material, args)
}

/// A scene on a loaded model and template; `args` gives the motion, shape and settings (its
/// garment, model and material fields are not read).
pub fn prepare_with(
    model: Arc<BodyModel>,
    garment: Arc<garments::Garment>,
    attachments: Vec<sim::scene::BodyAttachment>,
    material: sim::Material,
    args: &SceneArgs,
) -> Result<Prepared> {
    let shaped = model.shape(&args.betas)?;
    let motion = inputs::motion(&args.motion, &model, &shaped)?;
    let params = SolverParams {
        substeps: args.substeps,
        max_iterations: args.iterations,
        self_contact: !args.no_self_contact,
        self_contact_distance: args.self_contact_distance,
        self_friction: args.self_friction,
        ..SolverParams::default()
    };
    let scene = Scene {
        template: garment.positions.clone(),
        triangles: garment.triangles.clone(),
        betas: shaped.betas.clone(),
        motion,
        blend: BlendIn {
            blend_frames: args.blend_frames,
            settle_frames: args.settle_frames,
        },
        material,
        friction: args.friction,
        params,
        frames: args.frames,
        attachments,
    };
    scene.validate(&model)?;
    Ok(Prepared {
        model,
        garment,
        scene,
    })
}

/// Start of the error message of a run stopped by its deadline.
pub const TIMED_OUT: &str = "time limit reached";

/// What a recording carries besides the garment, and how the run shows itself.
#[derive(Debug, Clone, Copy, Default)]
pub struct RecordOptions<'a> {
    /// Record the body vertices of every frame.
    pub body_vertices: bool,
    /// Record a `foxglove.SceneUpdate` channel.
    pub foxglove: bool,
    /// Write OBJ frames into this folder, every K-th frame.
    pub obj: Option<(&'a Path, usize)>,
    /// Hide the progress bar.
    pub quiet: bool,
    /// The sequence's seed, recorded in its metadata.
    pub seed: Option<u64>,
    /// Give up (with an error saying so) when the run is still going at this moment.
    pub deadline: Option<Instant>,
}

/// Runs a prepared scene into `out` (atomically).
pub fn record(p: &Prepared, out: &Path, options: RecordOptions) -> Result<RunSummary> {
    let RecordOptions {
        body_vertices,
        foxglove,
        obj,
        quiet,
        seed,
        deadline,
    } = options;
    let frames = p.scene.num_frames();
    let meta = SequenceMeta {
        software: format!("dit-garment {}", env!("CARGO_PKG_VERSION")),
        garment: p.garment.name.clone(),
        motion: p.scene.motion.name.clone(),
        body_model: p.model.name().to_string(),
        betas: p.scene.betas.clone(),
        fps: FPS,
        frames,
        blend_frames: p.scene.blend.blend_frames,
        settle_frames: p.scene.blend.settle_frames,
        material: p.scene.material.into(),
        friction: p.scene.friction,
        seed,
        solver: p.scene.params,
        units: "metres, seconds, radians, kg; y up, body facing +z".into(),
    };
    let template = TemplateArrays {
        positions: p.garment.positions.clone(),
        triangles: p.garment.triangles.clone(),
        uvs: p.garment.uvs.clone(),
        uv_triangles: p.garment.uv_triangles.clone(),
    };
    let bar = ProgressBar::new(frames as u64).with_style(
        ProgressStyle::with_template(
            "simulating [{bar:30}] {pos}/{len} frames ({per_sec}, eta {eta})",
        )?
        .progress_chars("=> "),
    );
    if quiet {
        bar.set_draw_target(ProgressDrawTarget::hidden());
    }
    let mut summary = None;
    write_atomic(out, |w| {
        let faces = body_vertices.then(|| p.model.faces());
        let mut rec = RecordingWriter::new(w, &meta, &template, faces)?;
        if foxglove {
            rec = rec.with_foxglove_scene(&template.triangles, Some(p.model.faces()))?;
        }
        let s = p.scene.run(&p.model, |frame| {
            if deadline.is_some_and(|d| Instant::now() > d) {
                return Err(sim::Error::Recording {
                    path: out.display().to_string(),
                    message: format!("{TIMED_OUT} at frame {}", frame.index),
                });
            }
            rec.write_frame(frame, FPS)?;
            if let Some((dir, every)) = obj
                && frame.index % every.max(1) == 0
            {
                write_frame_objs(dir, p, frame).map_err(|e| sim::Error::Recording {
                    path: dir.display().to_string(),
                    message: format!("{e:#}"),
                })?;
            }
            bar.inc(1);
            Ok(())
        })?;
        rec.finish()?;
        summary = Some(s);
        Ok(())
    })?;
    bar.finish_and_clear();
    summary.context("the run produced no summary")
}

fn write_frame_objs(dir: &Path, p: &Prepared, frame: &sim::scene::FrameOutput) -> Result<()> {
    let k = frame.index;
    let positions: Vec<[f64; 3]> = frame.garment.iter().map(|v| [v.x, v.y, v.z]).collect();
    write_atomic(&dir.join(format!("garment_{k:04}.obj")), |w| {
        garments::write_obj(w, &p.garment, Some(&positions))?;
        Ok(())
    })?;
    write_atomic(&dir.join(format!("body_{k:04}.obj")), |w| {
        writeln!(w, "# body frame {k}")?;
        for v in &frame.body.vertices {
            writeln!(w, "v {:.6} {:.6} {:.6}", v[0], v[1], v[2])?;
        }
        for f in p.model.faces() {
            writeln!(w, "f {} {} {}", f[0] + 1, f[1] + 1, f[2] + 1)?;
        }
        Ok(())
    })
}

/// The machine-readable summary (keys checked by scripts).
pub fn summary_json(s: &RunSummary, out: &Path) -> serde_json::Value {
    json!({
        "frames": s.frames, "finite": s.finite, "wall_s": s.wall_s, "frames_per_s": s.frames_per_s,
        "max_penetration_m": s.max_penetration_m, "max_verts_inside": s.max_verts_inside,
        "max_edge_stretch": s.max_edge_stretch, "max_self_intersections": s.max_self_intersections,
        "vertices": s.vertices,
        "mean_iterations": s.mean_iterations, "deep_contacts": s.deep_contacts,
        "retried_frames": s.retried_frames, "stages_s": s.stages, "posing_s": s.posing_s,
        "recording": out,
    })
}

pub fn run(args: &SimulateArgs) -> Result<()> {
    let prepared = prepare(&args.scene)?;
    let obj = args.obj_dir.as_deref().map(|d| (d, args.obj_every));
    let options = RecordOptions {
        body_vertices: args.body_vertices,
        foxglove: args.foxglove,
        obj,
        quiet: args.quiet,
        ..RecordOptions::default()
    };
    let s = record(&prepared, &args.out, options)
        .with_context(|| format!("simulating into {}", args.out.display()))?;
    let summary = summary_json(&s, &args.out);
    if let Some(path) = &args.json {
        write_json(path, &summary)?;
    }
    println!(
        "simulate: '{}' ({} vertices) on '{}' through '{}': {} frames in {:.1} s ({:.1} frames/s)",
        prepared.garment.name,
        s.vertices,
        prepared.model.name(),
        prepared.scene.motion.name,
        s.frames,
        s.wall_s,
        s.frames_per_s
    );
    println!(
        "  max penetration {:.1} mm, at most {} vertices inside, max edge stretch {:.3}, at most {} self-intersections; wrote {}",
        s.max_penetration_m * 1e3,
        s.max_verts_inside,
        s.max_edge_stretch,
        s.max_self_intersections,
        args.out.display()
    );
    Ok(())
}
