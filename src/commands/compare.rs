//! `dit-garment compare A.mcap B.mcap`: B scored against A (ground truth) with the paper's
//! metrics (sim::metrics), every 5th frame, averaged; a table, per frame on request, and JSON.

use anyhow::{Result, bail};
use serde_json::json;
use sim::metrics::{BodySurface, FRAME_STRIDE, Scorer, Scores, jitter};
use sim::recording::Recording;

use crate::cli::CompareArgs;
use crate::inputs;
use crate::output::write_json;

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
    let a = Recording::read(&args.a)?;
    let b = Recording::read(&args.b)?;
    if a.template.triangles != b.template.triangles {
        bail!(
            "{} and {} do not share a garment template ({} vs {} triangles, or a different order)",
            args.a.display(),
            args.b.display(),
            a.template.triangles.len(),
            b.template.triangles.len()
        );
    }
    let frames = a.garment.len().min(b.garment.len());
    if frames == 0 {
        bail!("no frames to score");
    }
    let model = inputs::body_model(args.model.model.as_deref())?;
    let scorer = Scorer::new(&a.template.positions, &a.template.triangles, args.seed);
    let to64 =
        |f: &[[f32; 3]]| -> Vec<[f64; 3]> { f.iter().map(|p| p.map(|c| c as f64)).collect() };
    let mut per_frame = Vec::new();
    for k in (0..frames).step_by(FRAME_STRIDE) {
        let body = inputs::recorded_body(&model, &a, k, &args.a)?;
        let surface = BodySurface {
            vertices: &body.vertices,
            triangles: &body.faces,
        };
        let s = scorer.frame(
            &to64(&b.garment[k]),
            &to64(&a.garment[k]),
            Some(&surface),
            k,
        );
        if args.per_frame {
            println!(
                "frame {k:5}: {}",
                values(&s)
                    .iter()
                    .map(|v| format!("{v:9.4}"))
                    .collect::<Vec<_>>()
                    .join(" ")
            );
        }
        per_frame.push((k, s));
    }
    let mean = Scores::mean(&per_frame.iter().map(|(_, s)| *s).collect::<Vec<_>>());
    let all = |r: &Recording| -> Vec<Vec<[f64; 3]>> {
        r.garment[..frames].iter().map(|f| to64(f)).collect()
    };
    let (jitter_a, jitter_b) = (jitter(&all(&a)), jitter(&all(&b)));
    println!(
        "{} scored against {} ({} frames, every {FRAME_STRIDE}th):",
        args.b.display(),
        args.a.display(),
        per_frame.len()
    );
    for ((name, unit), v) in UNITS.iter().zip(values(&mean)) {
        println!("  {name:<11} {v:10.4}  {unit}");
    }
    println!(
        "  jitter      {jitter_b:10.4}  cm mean second difference over all {frames} frames (A: {jitter_a:.4})"
    );
    if let Some(path) = &args.json {
        let mut j = json!({
            "E_v": mean.E_v, "E_CD": mean.E_CD, "E_CD_cm": mean.E_CD_cm, "E_n": mean.E_n,
            "E_c": mean.E_c, "E_c_vertex": mean.E_c_vertex, "E_b": mean.E_b, "E_s": mean.E_s,
            "E_d": mean.E_d, "frames_scored": per_frame.len(),
            "units": UNITS.iter().map(|(n, u)| (n.to_string(), json!(u))).collect::<serde_json::Map<_, _>>(),
            "samples_per_mesh": sim::metrics::SAMPLES, "seed": args.seed,
            "jitter": jitter_b, "jitter_a": jitter_a, "frames": frames,
        });
        j["per_frame"] = per_frame
            .iter()
            .map(|(k, s)| json!({"frame": k, "scores": s}))
            .collect();
        write_json(path, &j)?;
    }
    Ok(())
}
