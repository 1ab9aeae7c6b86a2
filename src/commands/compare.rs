//! `dit-garment compare A.mcap B.mcap`: B scored against A (ground truth) with the paper's
//! metrics (sim::metrics), every 5th frame, averaged; a table, per frame on request, and JSON.

use anyhow::Result;
use serde_json::json;
use sim::metrics::{FRAME_STRIDE, Scores, compare_recordings};

use crate::cli::CompareArgs;
use files::write_json;

pub fn run(args: &CompareArgs) -> Result<()> {
    let model = sim::sources::body_model(args.model.body_model.as_deref())?;
    let c = compare_recordings(&args.a, &args.b, &model, args.seed)?;
    if args.per_frame {
        for (k, s) in &c.per_frame {
            say!(
                "frame {k:5}: {}",
                s.values()
                    .iter()
                    .map(|v| format!("{v:9.4}"))
                    .collect::<Vec<_>>()
                    .join(" ")
            );
        }
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
