//! `dit-garment compare A.mcap B.mcap`: B scored against A (ground truth) with the paper's
//! metrics (sim::metrics), every 5th frame, averaged; a table, per frame on request, and JSON.
//! `compare CAPTURE_DIR B.mcap`: B against a capture's frames of another topology, with the
//! correspondence-free metrics.

use anyhow::Result;
use serde_json::json;
use sim::metrics::{FRAME_STRIDE, Scores, compare_recordings};

use crate::cli::CompareArgs;
use files::write_json;

pub fn run(args: &CompareArgs) -> Result<()> {
    let model = sim::sources::body_model(args.model.body_model.as_deref())?;
    if args.a.is_dir() {
        return against_capture(args, &model);
    }
    let c = compare_recordings(&args.a, &args.b, &model, args.seed)?;
    if args.per_frame {
        print_frames(c.per_frame.iter().map(|(k, s)| (*k, s.values().to_vec())))?;
    }
    say!(
        "{} scored against {} ({} frames, every {FRAME_STRIDE}th):",
        args.b.display(),
        args.a.display(),
        c.per_frame.len()
    );
    for ((name, unit), v) in Scores::UNITS.iter().zip(c.mean.values()) {
        say!("  {name:<11} {v:10.4}  {unit}");
    }
    say!(
        "  jitter      {:10.4}  cm mean second difference over all {} frames (A: {:.4})",
        c.jitter_b,
        c.frames,
        c.jitter_a
    );
    if let Some(path) = &args.json {
        let mean = &c.mean;
        let mut j = json!({
            "E_v": mean.E_v, "E_CD": mean.E_CD, "E_CD_cm": mean.E_CD_cm, "E_n": mean.E_n,
            "E_c": mean.E_c, "E_c_vertex": mean.E_c_vertex, "E_b": mean.E_b, "E_s": mean.E_s,
            "E_d": mean.E_d, "frames_scored": c.per_frame.len(),
            "units": Scores::UNITS.iter().map(|(n, u)| (n.to_string(), json!(u))).collect::<serde_json::Map<_, _>>(),
            "samples_per_mesh": sim::metrics::SAMPLES, "seed": args.seed,
            "jitter": c.jitter_b, "jitter_a": c.jitter_a, "frames": c.frames,
        });
        j["per_frame"] = c
            .per_frame
            .iter()
            .map(|(k, s)| json!({"frame": k, "scores": s}))
            .collect();
        write_json(path, &j)?;
    }
    Ok(())
}

/// B scored against the capture frames in the folder A.
fn against_capture(args: &CompareArgs, model: &motions::BodyModel) -> Result<()> {
    let b = sim::recording::Recording::read(&args.b)?;
    let c = sim::metrics::compare_with_capture(
        &args.a,
        args.capture_garment.as_deref(),
        &b,
        &args.b,
        model,
        args.seed,
    )?;
    if args.per_frame {
        print_frames(c.per_frame.iter().map(|(k, s)| (*k, s.values().to_vec())))?;
    }
    say!(
        "{} scored against the capture {} ({} frames, every {FRAME_STRIDE}th; another topology):",
        args.b.display(),
        args.a.display(),
        c.per_frame.len()
    );
    for ((name, unit), v) in sim::metrics::CaptureScores::UNITS
        .iter()
        .zip(c.mean.values())
    {
        say!("  {name:<15} {v:10.4}  {unit}");
    }
    say!(
        "  not applicable (they need one vertex order on both sides): {}",
        sim::metrics::NOT_APPLICABLE.join(", ")
    );
    if let Some(path) = &args.json {
        let mut j = serde_json::to_value(c.mean)?;
        j["frames_scored"] = json!(c.per_frame.len());
        j["frames"] = json!(c.frames);
        j["not_applicable"] = json!(sim::metrics::NOT_APPLICABLE);
        j["units"] = sim::metrics::CaptureScores::UNITS
            .iter()
            .map(|(n, u)| (n.to_string(), json!(u)))
            .collect::<serde_json::Map<_, _>>()
            .into();
        j["samples_per_mesh"] = json!(sim::metrics::SAMPLES);
        j["seed"] = json!(args.seed);
        j["per_frame"] = c
            .per_frame
            .iter()
            .map(|(k, s)| json!({"frame": k, "scores": s}))
            .collect();
        write_json(path, &j)?;
    }
    Ok(())
}

/// One line per scored frame: its index and its values.
fn print_frames(rows: impl Iterator<Item = (usize, Vec<f64>)>) -> Result<()> {
    for (k, values) in rows {
        let cells: Vec<String> = values.iter().map(|v| format!("{v:9.4}")).collect();
        say!("frame {k:5}: {}", cells.join(" "));
    }
    Ok(())
}
