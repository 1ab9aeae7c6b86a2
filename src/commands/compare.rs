//! `dit-garment compare A.mcap B.mcap`: B scored against A (ground truth) with the paper's
//! metrics (sim::metrics), every 5th frame, averaged; a table, per frame on request, and JSON.

use std::path::Path;

use anyhow::{Result, bail};
use motions::BodyModel;
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

/// B scored against A: the mean of every 5th frame, each frame's scores, and both jitters.
pub struct Compared {
    pub mean: Scores,
    pub per_frame: Vec<(usize, Scores)>,
    /// Frames both recordings have.
    pub frames: usize,
    /// Mean |second difference| of vertex positions over all frames, cm.
    pub jitter_a: f64,
    pub jitter_b: f64,
}

/// Scores recording `b` against recording `a` (ground truth, same template) with the body of
/// `model` (E_c), every 5th frame.
pub fn score(a_path: &Path, b_path: &Path, model: &BodyModel, seed: u64) -> Result<Compared> {
    let a = Recording::read(a_path)?;
    let b = Recording::read(b_path)?;
    if a.template.triangles != b.template.triangles {
        bail!(
            "{} and {} do not share a garment template ({} vs {} triangles, or a different order)",
            a_path.display(),
            b_path.display(),
            a.template.triangles.len(),
            b.template.triangles.len()
        );
    }
    let frames = a.garment.len().min(b.garment.len());
    if frames == 0 {
        bail!(
            "no frames to score: {} has {}, {} has {}",
            a_path.display(),
            a.garment.len(),
            b_path.display(),
            b.garment.len()
        );
    }
    let scorer = Scorer::new(&a.template.positions, &a.template.triangles, seed);
    let to64 =
        |f: &[[f32; 3]]| -> Vec<[f64; 3]> { f.iter().map(|p| p.map(|c| c as f64)).collect() };
    let mut per_frame = Vec::new();
    for k in (0..frames).step_by(FRAME_STRIDE) {
        let body = inputs::recorded_body(model, &a, k, a_path)?;
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
        per_frame.push((k, s));
    }
    let mean = Scores::mean(&per_frame.iter().map(|(_, s)| *s).collect::<Vec<_>>());
    let all = |r: &Recording| -> Vec<Vec<[f64; 3]>> {
        r.garment[..frames].iter().map(|f| to64(f)).collect()
    };
    Ok(Compared {
        mean,
        per_frame,
        frames,
        jitter_a: jitter(&all(&a)),
        jitter_b: jitter(&all(&b)),
    })
}

pub fn run(args: &CompareArgs) -> Result<()> {
    let model = inputs::body_model(args.model.model.as_deref())?;
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
