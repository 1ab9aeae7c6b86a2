//! End-to-end: `garments import`, a user's own garment made a template. A library design is
//! sewn, worn through a motion by a shaped body, one frame written as a plain mesh without UVs
//! (as a capture gives it), and that mesh imported back from that frame's pose: the template
//! comes back near the design's own, with UVs of its own. A mesh with overlapping UVs is
//! unwrapped again; one with a non-manifold edge is refused by name with nothing written.

mod common;

use std::path::{Path, PathBuf};
use std::sync::OnceLock;

use common::{fails, json, ok};
use serde_json::Value;

fn s(p: &Path) -> &str {
    p.to_str().unwrap()
}

/// The shape of the body that wears the garment.
const BETAS: &str = "1.0,-0.5";
/// The recording's frame written as a mesh: blend 10 + settle 5 frames, then motion frame 3.
const RECORDED_FRAME: usize = 18;
const MOTION_FRAME: &str = "3";

struct Worn {
    dir: PathBuf,
    /// The design's template.
    template: PathBuf,
    /// One frame of it worn, as a plain mesh (positions and triangles only).
    plain: PathBuf,
}

/// A coarse `tank_tight` template, worn through `walk` by a shaped body, frame 18 written
/// without UVs.
fn worn() -> &'static Worn {
    static WORN: OnceLock<Worn> = OnceLock::new();
    WORN.get_or_init(|| {
        let dir = std::env::temp_dir().join(format!("dit-garment-import-{}", std::process::id()));
        let _ = std::fs::remove_dir_all(&dir);
        std::fs::create_dir_all(&dir).unwrap();
        let template = dir.join("tank.obj");
        ok(&[
            "garments",
            "make",
            "tank_tight",
            "--edge-length",
            "0.03",
            "--out",
            s(&template),
        ]);
        let frames = dir.join("frames");
        ok(&[
            "simulate",
            "--garment",
            s(&template),
            "--motion",
            "walk",
            "--betas",
            BETAS,
            "--blend-frames",
            "10",
            "--settle-frames",
            "5",
            "--frames",
            "19",
            "--out",
            s(&dir.join("worn.mcap")),
            "--obj-dir",
            s(&frames),
            "--obj-every",
            "1",
            "--quiet",
        ]);
        let obj = std::fs::read_to_string(frames.join(format!("garment_{RECORDED_FRAME:04}.obj")))
            .unwrap();
        let plain: String = obj
            .lines()
            .filter(|l| l.starts_with("v "))
            .map(|l| format!("{l}\n"))
            .chain(obj.lines().filter(|l| l.starts_with("f ")).map(|l| {
                let corners: Vec<&str> = l[2..]
                    .split_whitespace()
                    .map(|c| c.split('/').next().unwrap())
                    .collect();
                format!("f {}\n", corners.join(" "))
            }))
            .collect();
        let plain_path = dir.join("worn_frame.obj");
        std::fs::write(&plain_path, plain).unwrap();
        Worn {
            dir,
            template,
            plain: plain_path,
        }
    })
}

fn positions(path: &Path) -> Vec<[f64; 3]> {
    std::fs::read_to_string(path)
        .unwrap()
        .lines()
        .filter_map(|l| l.strip_prefix("v "))
        .map(|l| {
            let v: Vec<f64> = l.split_whitespace().map(|x| x.parse().unwrap()).collect();
            [v[0], v[1], v[2]]
        })
        .collect()
}

/// The symmetric mean nearest-point distance between two point sets, cm (`E_CD_cm`).
fn chamfer_cm(a: &[[f64; 3]], b: &[[f64; 3]]) -> f64 {
    let one_way = |x: &[[f64; 3]], y: &[[f64; 3]]| {
        x.iter()
            .map(|p| {
                y.iter()
                    .map(|q| (0..3).map(|k| (p[k] - q[k]).powi(2)).sum::<f64>())
                    .fold(f64::MAX, f64::min)
                    .sqrt()
            })
            .sum::<f64>()
            / x.len() as f64
    };
    50.0 * (one_way(a, b) + one_way(b, a))
}

fn import(mesh: &Path, out: &Path, report: &Path) -> Vec<String> {
    [
        "garments",
        "import",
        s(mesh),
        "--motion",
        "walk",
        "--frame",
        MOTION_FRAME,
        "--betas",
        BETAS,
        "--out",
        s(out),
        "--report",
        s(report),
    ]
    .map(String::from)
    .to_vec()
}

fn args(v: &[String]) -> Vec<&str> {
    v.iter().map(String::as_str).collect()
}

#[test]
fn a_worn_frame_without_uvs_comes_back_as_the_designs_template() {
    let w = worn();
    let (out, report) = (w.dir.join("imported.obj"), w.dir.join("imported.json"));
    let said = ok(&args(&import(&w.plain, &out, &report)));
    assert!(said.contains("gates passed"), "{said}");
    let r: Value = json(&report);
    assert_eq!(r["uvs"], "none", "{r}");
    assert_eq!(r["drape"]["gates_passed"], true, "{r}");
    assert!(r["unposed_mean_m"].as_f64().unwrap() > 0.01, "{r}");
    let back = garments::read_obj(&out).unwrap();
    assert_eq!(
        back.uv_triangles.len(),
        back.triangles.len(),
        "UVs of its own"
    );
    assert!(garments::uv_overlap(&back) < 0.02);
    let (template, worn_frame) = (positions(&w.template), positions(&w.plain));
    let before = chamfer_cm(&worn_frame, &template);
    let after = chamfer_cm(&back.positions, &template);
    // Measured 2026-12-05: see docs/GARMENTS.md "A user's own garment".
    assert!(
        after < 0.5 * before,
        "worn {before:.2} cm, imported {after:.2} cm"
    );
    assert!(after < 2.0, "imported {after:.2} cm from the template");
}

#[test]
fn overlapping_uvs_are_unwrapped_again_and_a_non_manifold_mesh_is_refused() {
    let w = worn();
    let text = std::fs::read_to_string(&w.plain).unwrap();
    // Every corner on one UV point: charts lie on each other.
    let overlapping: String = text
        .lines()
        .map(|l| match l.strip_prefix("f ") {
            Some(f) => {
                let c: Vec<String> = f.split_whitespace().map(|v| format!("{v}/1")).collect();
                format!("f {}\n", c.join(" "))
            }
            None => format!("{l}\n"),
        })
        .collect();
    let overlapping = format!("vt 0.5 0.5\n{overlapping}");
    let path = w.dir.join("overlapping.obj");
    std::fs::write(&path, overlapping).unwrap();
    let (out, report) = (w.dir.join("unwrapped.obj"), w.dir.join("unwrapped.json"));
    ok(&args(&import(&path, &out, &report)));
    let r: Value = json(&report);
    assert_eq!(r["uvs"], "overlapping", "{r}");
    assert!(r["uv_overlap_read"].as_f64().unwrap() > 0.9, "{r}");

    // Three triangles on one edge: refused, naming the fault.
    let first = text.lines().find(|l| l.starts_with("f ")).unwrap();
    let c: Vec<&str> = first[2..].split_whitespace().collect();
    let fin = format!(
        "{text}v 0 2 0\nv 0 2.1 0\nf {} {} {}\nf {} {} {}\n",
        c[0],
        c[1],
        positions(&w.plain).len() + 1,
        c[0],
        c[1],
        positions(&w.plain).len() + 2
    );
    let path = w.dir.join("fin.obj");
    std::fs::write(&path, fin).unwrap();
    let (out, report) = (w.dir.join("fin_out.obj"), w.dir.join("fin.json"));
    let e = fails(&args(&import(&path, &out, &report)));
    assert!(e.contains("non-manifold edges"), "{e}");
    assert!(!out.exists() && !report.exists(), "nothing written");

    // A frame past the motion's end is named.
    let mut late = import(&w.plain, &out, &report);
    late[6] = "100000".into();
    let e = fails(&args(&late));
    assert!(e.contains("--frame 100000"), "{e}");
}
