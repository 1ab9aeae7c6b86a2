//! Same inputs, same bytes: the default garment scene (self-contact on) simulated in separate
//! processes at different thread counts writes identical recordings.

mod common;

use common::run_with;
use sim::recording::Recording;

#[test]
fn the_default_scene_gives_the_same_bytes_across_processes_and_thread_counts() {
    let dir = tempfile::tempdir().unwrap();
    let mut recordings = Vec::new();
    for threads in ["1", "2", "3"] {
        let out = dir.path().join(format!("threads{threads}.mcap"));
        let run = run_with(
            &[
                "simulate",
                "--quiet",
                "--frames",
                "8",
                "--blend-frames",
                "2",
                "--settle-frames",
                "1",
                "--out",
                out.to_str().unwrap(),
            ],
            &[("RAYON_NUM_THREADS", threads)],
        );
        assert!(
            run.status.success(),
            "{}",
            String::from_utf8_lossy(&run.stderr)
        );
        recordings.push((threads, out));
    }
    let first = Recording::read(&recordings[0].1).unwrap();
    let config = first.meta.as_ref().unwrap().scene_config().unwrap();
    assert!(
        config.solver.self_contact,
        "the default scene has self-contact on"
    );
    let bytes = std::fs::read(&recordings[0].1).unwrap();
    for (threads, path) in &recordings[1..] {
        if std::fs::read(path).unwrap() != bytes {
            let other = Recording::read(path).unwrap();
            let frame = (0..first.garment.len()).find(|&k| first.garment[k] != other.garment[k]);
            panic!("{threads} threads differ from 1 (first differing frame: {frame:?})");
        }
    }
}
