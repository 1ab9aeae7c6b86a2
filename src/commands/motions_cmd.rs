//! `dit-garment motions list|show|export`.

use anyhow::Result;
use motions::library::{MOTIONS, MotionSpec};
use motions::{BlendIn, JOINT_NAMES, MAX_PREFIX_FRAMES, MotionSource};
use serde_json::json;
use sim::recording::write_body_sequence;

use crate::cli::MotionsCommand;
use files::write_json;

pub fn run(command: MotionsCommand) -> Result<()> {
    match command {
        MotionsCommand::List { json } => list(json.as_deref()),
        MotionsCommand::Show {
            motion,
            model,
            json,
        } => show(&motion, model.body_model.as_deref(), json.as_deref()),
        MotionsCommand::Export {
            motion,
            out,
            model,
            betas,
            blend_frames,
            settle_frames,
            json,
        } => {
            for (flag, value) in [
                ("--blend-frames", blend_frames),
                ("--settle-frames", settle_frames),
            ] {
                anyhow::ensure!(
                    value <= MAX_PREFIX_FRAMES,
                    "{flag} {value}: at most {MAX_PREFIX_FRAMES} (an hour at 30 fps)"
                );
            }
            let model = sim::sources::body_model(model.body_model.as_deref())?;
            let shaped = model.shape(&betas)?;
            let motion = sim::sources::motion(&motion, &model, &shaped)?;
            if out
                .extension()
                .is_some_and(|e| e.eq_ignore_ascii_case("npz"))
            {
                files::create_folder_of(&out)?;
                motions::amass::write(&out, &motion, shaped.joints[0], &betas)?;
                say!(
                    "wrote {} (AMASS-style: {} frames at {} fps, {:.2} s, z up)",
                    out.display(),
                    motion.len(),
                    motion.fps,
                    motion.duration()
                );
                if let Some(path) = json {
                    let bytes = std::fs::metadata(&out)?.len();
                    write_json(
                        &path,
                        &json!({"frames": motion.len(), "fps": motion.fps, "bytes": bytes, "file": out}),
                    )?;
                }
                return Ok(());
            }
            let blend = BlendIn {
                blend_frames,
                settle_frames,
            };
            let software = format!("dit-garment {}", env!("CARGO_PKG_VERSION"));
            let m = write_body_sequence(&out, &model, &betas, &motion, blend, &software)?;
            let bytes = std::fs::metadata(&out)?.len();
            say!(
                "wrote {} ({} frames at {} fps, {} vertices, {:.1} MB)",
                out.display(),
                m.frames,
                m.fps,
                model.num_vertices(),
                bytes as f64 / 1e6
            );
            if let Some(path) = json {
                write_json(
                    &path,
                    &json!({"frames": m.frames, "fps": m.fps, "vertices": model.num_vertices(), "bytes": bytes, "file": out}),
                )?;
            }
            Ok(())
        }
    }
}

fn list(json_path: Option<&std::path::Path>) -> Result<()> {
    say!(
        "{:<15} {:>6} {:>9}  description",
        "name",
        "frames",
        "seconds"
    );
    let mut rows = Vec::new();
    for info in MOTIONS {
        let spec = MotionSpec::parse(info.name)?;
        let frames = (spec.duration * 30.0).round() as usize;
        say!(
            "{:<15} {:>6} {:>9.2}  {}",
            info.name,
            frames,
            spec.duration,
            info.description
        );
        rows.push(json!({"name": info.name, "frames": frames, "fps": 30.0, "duration_s": spec.duration, "description": info.description,
            "parameters": {"speed": "tempo multiplier, 0.25-3, default 1", "amplitude": "joint-angle multiplier, 0-1.5, default 1", "duration": "seconds, default as listed", "seed": "random only: which random motion, a whole number, default 0"}}));
    }
    say!(
        "\nvariants: NAME:speed=1.3,amplitude=0.8,duration=6 (and random:seed=N); AMASS .npz and BVH files are accepted wherever a motion is, as FILE or FILE:start=S,duration=D (BVH: also map=JOINTS.toml)"
    );
    if let Some(path) = json_path {
        write_json(path, &rows)?;
    }
    Ok(())
}

fn show(
    source: &str,
    model_path: Option<&std::path::Path>,
    json_path: Option<&std::path::Path>,
) -> Result<()> {
    let model = sim::sources::body_model(model_path)?;
    let loaded = MotionSource::parse(source)?.load(&model, &model.shape(&[])?)?;
    let motion = &loaded.motion;
    let (first, last) = (
        motion.frames[0].transl,
        motion.frames[motion.len() - 1].transl,
    );
    let travel: [f64; 3] = std::array::from_fn(|k| last[k] - first[k]);
    let max_angle = motion.max_joint_angles_deg();
    say!("motion    {}", motion.name);
    let (frames, fps, duration) = (motion.len(), motion.fps, motion.duration());
    say!("frames    {frames} at {fps} fps ({duration:.2} s)");
    let [x, y, z] = travel;
    say!("root      travel x {x:+.3} y {y:+.3} z {z:+.3} m");
    if let Some(r) = &loaded.retarget {
        say!(
            "source    {} frames at {:.2} fps{}; {} up, facing {}; {:.6} m per unit (from the {})",
            r.source_frames,
            r.source_fps,
            if r.reference_frame_dropped {
                " (the first, a reference pose, dropped)"
            } else {
                ""
            },
            r.up_axis,
            r.forward_axis,
            r.metres_per_unit,
            r.scale_from
        );
        let pairs: Vec<String> = r.mapped.iter().map(|(s, b)| format!("{s}<-{b}")).collect();
        say!(
            "mapped    {} joints ({} map): {}",
            pairs.len(),
            r.map,
            pairs.join(" ")
        );
        say!(
            "dropped   {} BVH joints: {}",
            r.dropped.len(),
            r.dropped.join(" ")
        );
        if !r.unmapped.is_empty() {
            say!(
                "unmapped  {} SMPL joints (follow their parent): {}",
                r.unmapped.len(),
                r.unmapped.join(" ")
            );
        }
    }
    say!("joint rotation ranges (degrees from the T-pose, max over frames):");
    for (name, deg) in JOINT_NAMES
        .iter()
        .zip(&max_angle)
        .filter(|(_, d)| **d > 0.5)
    {
        say!("  {name:<15} {deg:>6.1}");
    }
    if let Some(path) = json_path {
        let mut summary = json!({
            "name": motion.name, "frames": frames, "fps": fps, "duration_s": duration,
            "root_travel_m": travel, "max_joint_angle_deg": max_angle, "joint_names": JOINT_NAMES,
            "gender": motion.gender, "betas": motion.betas,
        });
        if let Some(r) = &loaded.retarget {
            summary["source"] = json!({"format": "bvh", "frames": r.source_frames, "fps": r.source_fps,
                "reference_frame_dropped": r.reference_frame_dropped, "up_axis": r.up_axis,
                "forward_axis": r.forward_axis, "metres_per_unit": r.metres_per_unit,
                "scale_from": r.scale_from, "joint_map": r.map});
            summary["mapped_joints"] = r
                .mapped
                .iter()
                .map(|(s, b)| (s.to_string(), json!(b)))
                .collect::<serde_json::Map<_, _>>()
                .into();
            summary["dropped_joints"] = json!(r.dropped);
            summary["unmapped_joints"] = json!(r.unmapped);
        }
        write_json(path, &summary)?;
    }
    Ok(())
}
