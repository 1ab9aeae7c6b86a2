//! `dit-garment demo`: the main job on built-in defaults. For now it poses the default body
//! through a built-in motion (blend-in from the canonical A-pose included) and writes the
//! sequence as MCAP, every K-th frame as OBJ, and a JSON summary.

use std::collections::BTreeMap;
use std::time::Instant;

use anyhow::Result;
use indicatif::{ProgressBar, ProgressStyle};
use motions::{BlendIn, BodyModel, canonical_a_pose};
use rayon::prelude::*;
use serde_json::json;

use crate::cli::DemoArgs;
use crate::inputs;
use crate::output::{write_atomic, write_json, write_obj};
use crate::recording::write_body_sequence;

pub fn run(args: &DemoArgs) -> Result<()> {
    let started = Instant::now();
    std::fs::create_dir_all(&args.out)?;
    let model = BodyModel::default_body();
    let shaped = model.shape(&[])?;
    let blend = BlendIn::default();
    let motion =
        inputs::motion(&args.motion, &model, &shaped)?.with_blend_in(&canonical_a_pose(), blend);

    let bar = ProgressBar::new(motion.len() as u64).with_style(
        ProgressStyle::with_template(
            "{msg:>8} [{bar:30}] {pos}/{len} frames ({per_sec}, eta {eta})",
        )?
        .progress_chars("=> "),
    );
    bar.set_message("posing");
    let pose_start = Instant::now();
    let posed = motion
        .frames
        .par_iter()
        .map(|f| {
            let p = model.pose(&shaped, f);
            bar.inc(1);
            p
        })
        .collect::<Result<Vec<_>, _>>()?;
    let pose_seconds = pose_start.elapsed().as_secs_f64();
    bar.finish_and_clear();

    let sequence = args.out.join("body.mcap");
    let extra = BTreeMap::from([
        ("blend_frames".to_string(), blend.blend_frames.to_string()),
        ("settle_frames".to_string(), blend.settle_frames.to_string()),
    ]);
    write_atomic(&sequence, |w| {
        write_body_sequence(w, &model, &shaped, &motion, &posed, &extra)
    })?;
    let mut objs = Vec::new();
    if args.obj_every > 0 {
        for k in (0..posed.len()).step_by(args.obj_every) {
            let path = args.out.join("frames").join(format!("body_{k:04}.obj"));
            write_obj(
                &path,
                &posed[k].vertices,
                model.faces(),
                &format!("dit-garment demo: {} frame {k}", motion.name),
            )?;
            objs.push(path);
        }
    }
    let summary = json!({
        "motion": motion.name, "frames": motion.len(), "fps": motion.fps,
        "blend_frames": blend.blend_frames, "settle_frames": blend.settle_frames,
        "vertices": model.num_vertices(), "boundary_edges": model.boundary_edge_count(),
        "height_m": super::height(&shaped.vertices),
        "root_travel_m": (0..3).map(|c| motion.frames[motion.len() - 1].transl[c] - motion.frames[0].transl[c]).collect::<Vec<_>>(),
        "posing_frames_per_s": motion.len() as f64 / pose_seconds,
        "sequence": sequence, "obj_frames": objs.len(), "wall_s": started.elapsed().as_secs_f64(),
    });
    write_json(&args.out.join("summary.json"), &summary)?;
    if let Some(path) = &args.json {
        write_json(path, &summary)?;
    }
    println!(
        "demo: default body ({} vertices, closed) through '{}': {} frames at 30 fps ({} blend-in + {} settle)",
        model.num_vertices(),
        motion.name,
        motion.len(),
        blend.blend_frames,
        blend.settle_frames
    );
    println!(
        "  posed at {:.0} frames/s; wrote {}, {} OBJ frames in {}, summary.json",
        motion.len() as f64 / pose_seconds,
        sequence.display(),
        objs.len(),
        args.out.join("frames").display()
    );
    Ok(())
}
