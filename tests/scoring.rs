//! `compare` against hand values: a recording and its copy shifted 1 mm further every frame.

mod common;

use std::path::Path;

use common::{json, ok};
use sim::recording::{Channels, FrameRecord, Recording, SequenceWriter};

/// Writes `a` again with frame k's garment moved `step_m * k` up.
fn shifted_copy(a: &Recording, step_m: f64, out: &Path) {
    let file = std::io::BufWriter::new(std::fs::File::create(out).unwrap());
    let meta = a.meta.clone().unwrap();
    let channels = Channels {
        template: Some(&a.template),
        ..Default::default()
    };
    let mut writer = SequenceWriter::new(file, &meta, channels, meta.fps).unwrap();
    for (k, (garment, pose)) in a.garment.iter().zip(&a.poses).enumerate() {
        let moved: Vec<[f64; 3]> = garment
            .iter()
            .map(|p| [p[0] as f64, p[1] as f64 + step_m * k as f64, p[2] as f64])
            .collect();
        let mut pose72 = [0.0; 72];
        pose72.copy_from_slice(&pose.pose);
        writer
            .write_frame(&FrameRecord {
                index: k,
                garment: Some(&moved),
                pose: &pose72,
                transl: pose.transl,
                betas: &pose.betas,
                body_vertices: None,
                joints: None,
                stats: None,
            })
            .unwrap();
    }
    writer.finish().unwrap();
}

/// 12 frames, B shifted 0.1 k cm at frame k: compare scores frames 0, 5 and 10, so E_v and
/// E_d are (0 + 0.5 + 1.0) / 3 = 0.5 cm (all 12 frames would give 0.55, frames 1, 6, 11 give
/// 0.6). (E_CD has no hand value here: a vertical shift slides along most of the skirt.)
#[test]
fn compare_averages_every_fifth_frame() {
    let dir = tempfile::tempdir().unwrap();
    let (a, b) = (dir.path().join("a.mcap"), dir.path().join("b.mcap"));
    ok(&[
        "simulate",
        "--quiet",
        "--frames",
        "12",
        "--blend-frames",
        "2",
        "--settle-frames",
        "1",
        "--out",
        a.to_str().unwrap(),
    ]);
    let recording = Recording::read(&a).unwrap();
    assert_eq!(recording.garment.len(), 12);
    shifted_copy(&recording, 0.001, &b);
    let scores = dir.path().join("scores.json");
    ok(&[
        "compare",
        a.to_str().unwrap(),
        b.to_str().unwrap(),
        "--per-frame",
        "--json",
        scores.to_str().unwrap(),
    ]);
    let j = json(&scores);
    assert_eq!(j["frames_scored"], 3);
    // Frames are stored as f32: positions near 1 m carry about 1e-7 m of rounding.
    for key in ["E_v", "E_d"] {
        let v = j[key].as_f64().unwrap();
        assert!((v - 0.5).abs() < 1e-4, "{key} {v}, expected 0.5 cm");
    }
    let frames: Vec<u64> = j["per_frame"]
        .as_array()
        .unwrap()
        .iter()
        .map(|f| f["frame"].as_u64().unwrap())
        .collect();
    assert_eq!(frames, [0, 5, 10]);
}
