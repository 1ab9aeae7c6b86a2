//! `dit-garment compare A.mcap B.mcap`: B scored against A (ground truth) with the paper's
//! metrics (sim::metrics), every 5th frame, averaged; a table, per frame on request, and JSON.

use anyhow::Result;
use serde_json::json;
use sim::metrics::{FRAME_STRIDE, Scores};

use crate::cli::CompareArgs;
use crate::output::write_json;
use crate::scoring::score;

const UNITS: [(&str, &str); 9] = [
    ("E_v", "cm"),
    ("E_CD", "100 m^2 (squared distances)"),
    ("E_CD_cm", "cm"),
    ("E_n", "1 (sum of both directions)"),
    ("E_c", "% of garment surface samples inside the body"),
    ("E_c_vertex", "% of garment vertices inside the body"),
    ("E_b", "rad"),
    ("E_s", "1 (x 1e5)"),
    ("E_d", "cm"),
];

fn values(s: &Scores) -> [f64; 9] {
    [
        s.E_v,
        s.E_CD,
        s.E_CD_cm,
        s.E_n,
        s.E_c,
        s.E_c_vertex,
        s.E_b,
        s.E_s,
        s.E_d,
    ]
}

pub fn run(args: &CompareArgs) -> Result<()> {
    let model = sim::sources::body_model(args.model.body_model.as_deref())?;
    let c = score(&args.a, &args.b, &model, args.seed)?;
    if args.per_frame {
        for (k, s) in &c.per_frame {
            println!(
                "frame {k:5}: {}",
                values(s)
                    .iter()
                    .map(|v| format!("{v:9.4}"))
                    .collect::<Vec<_>>()
                    .join(" ")
            );
        }
    }
    println!(
        "{} scored against {} ({} frames, every {FRAME_STRIDE}th):",
        args.b.display(),
        args.a.display(),
        c.per_frame.len()
    );
    for ((name, unit), v) in UNITS.iter().zip(values(&c.mean)) {
        println!("  {name:<11} {v:10.4}  {unit}");
    }
    println!(
        "  jitter      {:10.4}  cm mean second difference over all {} frames (A: {:.4})",
        c.jitter_b, c.frames, c.jitter_a
    );
    if let Some(path) = &args.json {
        let mean = &c.mean;
        let mut j = json!({
            "E_v": mean.E_v, "E_CD": mean.E_CD, "E_CD_cm": mean.E_CD_cm, "E_n": mean.E_n,
            "E_c": mean.E_c, "E_c_vertex": mean.E_c_vertex, "E_b": mean.E_b, "E_s": mean.E_s,
            "E_d": mean.E_d, "frames_scored": c.per_frame.len(),
            "units": UNITS.iter().map(|(n, u)| (n.to_string(), json!(u))).collect::<serde_json::Map<_, _>>(),
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
