//! End-to-end: the `dit-garment` binary as a user runs it, outputs read back with public
//! libraries (mcap, serde_json), and bad input failing cleanly with nothing half-written.

mod common;

use std::path::Path;

use common::{fails, json, ok};

/// Counts MCAP messages per topic.
fn topics(path: &Path) -> std::collections::BTreeMap<String, usize> {
    let bytes = std::fs::read(path).unwrap();
    let mut counts = std::collections::BTreeMap::new();
    for message in mcap::MessageStream::new(&bytes).unwrap() {
        *counts
            .entry(message.unwrap().channel.topic.clone())
            .or_insert(0) += 1;
    }
    counts
}

#[test]
fn demo_writes_a_readable_sequence_and_summary() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("demo");
    let stdout = ok(&[
        "demo",
        "--out",
        out.to_str().unwrap(),
        "--motion",
        "walk:duration=1",
        "--frames",
        "8",
        "--obj-every",
        "4",
    ]);
    assert!(stdout.contains("default body"), "{stdout}");
    let summary = json(&out.join("summary.json"));
    assert_eq!(summary["frames"], 8);
    assert_eq!(summary["finite"], true);
    let counts = topics(&out.join("sequence.mcap"));
    assert_eq!(counts["/garment/vertices"], 8);
    assert_eq!(counts["/body/pose"], 8);
    assert_eq!(counts["/sim/stats"], 8);
    assert_eq!(counts["/sequence/meta"], 1);
    assert_eq!(counts["/garment/template/uvs"], 1);
    let recording = sim::recording::Recording::read(&out.join("sequence.mcap")).unwrap();
    assert_eq!(recording.garment.len(), 8);
    assert_eq!(recording.meta.unwrap().material.stretch, 100.0);
    assert!(out.join("frames/garment_0004.obj").exists());
    assert!(out.join("frames/body_0004.obj").exists());
    for preview in [
        "pictures/contact_sheet.png",
        "pictures/sequence.gif",
        "pictures/comparison_sheet.png",
        "pictures/comparison.gif",
        "predicted.mcap",
        "view.html",
    ] {
        assert!(out.join(preview).exists(), "demo did not write {preview}");
    }
    assert_eq!(summary["viewer"], out.join("view.html").to_str().unwrap());
    // The shipped surrogate predicted the same 8 frames, scored against the simulation.
    let predicted = &summary["predicted"];
    for key in [
        "recording",
        "frames",
        "frames_per_s",
        "E_v",
        "E_CD",
        "E_n",
        "E_c",
        "E_b",
        "E_s",
        "E_d",
        "model",
        "steps",
        "guidance",
    ] {
        assert!(!predicted[key].is_null(), "summary.predicted lacks {key}");
    }
    assert_eq!(predicted["frames"], 8);
    assert_eq!(predicted["model"], "builtin");
    assert_eq!(predicted["template_seen_in_training"], false);
    let e_v = predicted["E_v"].as_f64().unwrap();
    assert!(e_v > 0.0 && e_v < 20.0, "E_v {e_v} cm");
    assert!(summary["speedup"].as_f64().unwrap() > 0.0);
    assert_eq!(
        summary["comparison_sheet"],
        out.join("pictures/comparison_sheet.png").to_str().unwrap()
    );
    let predicted_recording = sim::recording::Recording::read(&out.join("predicted.mcap")).unwrap();
    assert_eq!(predicted_recording.garment.len(), 8);
    assert!(stdout.contains("predicted"), "{stdout}");
    assert!(
        std::fs::read_dir(&out).unwrap().all(|e| !e
            .unwrap()
            .file_name()
            .to_string_lossy()
            .ends_with(".tmp"))
    );
}

/// A missing or damaged surrogate stops the demo before it simulates, with an error naming
/// it; `--surrogate none` simulates only.
#[test]
fn demo_refuses_a_bad_surrogate_and_runs_without_one() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("demo");
    let o = out.to_str().unwrap();
    let missing = dir.path().join("no-run");
    let stderr = fails(&["demo", "--out", o, "--surrogate", missing.to_str().unwrap()]);
    assert!(stderr.contains("no-run"), "{stderr}");
    let damaged = dir.path().join("damaged");
    std::fs::create_dir_all(&damaged).unwrap();
    let weights = Path::new(env!("CARGO_MANIFEST_DIR")).join("surrogate/weights");
    for file in ["config.toml", "tensors.json"] {
        std::fs::copy(weights.join(file), damaged.join(file)).unwrap();
    }
    let mut bytes = std::fs::read(weights.join("model.safetensors")).unwrap();
    bytes.truncate(bytes.len() / 2);
    std::fs::write(damaged.join("model.safetensors"), bytes).unwrap();
    let stderr = fails(&["demo", "--out", o, "--surrogate", damaged.to_str().unwrap()]);
    assert!(stderr.contains("model.safetensors"), "{stderr}");
    assert!(!out.join("sequence.mcap").exists());
    ok(&[
        "demo",
        "--out",
        o,
        "--motion",
        "walk:duration=1",
        "--frames",
        "3",
        "--surrogate",
        "none",
    ]);
    let summary = json(&out.join("summary.json"));
    assert!(summary.get("predicted").is_none());
    assert!(!out.join("predicted.mcap").exists());
}

#[test]
fn simulate_reports_the_checked_keys_and_rejects_bad_settings() {
    let dir = tempfile::tempdir().unwrap();
    let seq = dir.path().join("seq.mcap");
    let stats = dir.path().join("stats.json");
    ok(&[
        "simulate",
        "--motion",
        "jumping_jacks:duration=1",
        "--betas",
        "1.5,0.5",
        "--material",
        "k_s=150,rho=0.3,k_b=1e-6",
        "--friction",
        "0",
        "--frames",
        "6",
        "--out",
        seq.to_str().unwrap(),
        "--json",
        stats.to_str().unwrap(),
        "--quiet",
    ]);
    let j = json(&stats);
    for key in [
        "frames",
        "finite",
        "wall_s",
        "frames_per_s",
        "max_penetration_m",
        "max_verts_inside",
        "max_penetration_overlap_m",
        "max_verts_inside_overlap",
        "max_self_intersections",
        "max_edge_stretch",
        "vertices",
    ] {
        assert!(j.get(key).is_some(), "missing key {key} in {j}");
    }
    assert_eq!(j["frames"], 6);
    for (flags, expected) in [
        (vec!["--material", "k_s=-1"], "k_s"),
        (vec!["--material", "rho=0"], "rho"),
        (vec!["--material", "k_b=abc"], "not a number"),
        (vec!["--friction=-0.5"], "friction"),
        (vec!["--motion", "missing.npz"], "missing.npz"),
        (vec!["--garment", "missing.obj"], "missing.obj"),
        (vec!["--garment", "cape"], "unknown garment"),
        (
            vec!["--self-contact-distance=-0.001"],
            "self_contact_distance",
        ),
        (vec!["--self-contact-distance=0"], "self_contact_distance"),
        (vec!["--self-friction=-1"], "self_friction"),
        (vec!["--acceleration", "9"], "acceleration"),
    ] {
        let mut args = vec![
            "simulate",
            "--frames",
            "2",
            "--out",
            seq.to_str().unwrap(),
            "--quiet",
        ];
        args.extend(flags);
        let err = fails(&args);
        assert!(err.contains(expected), "{args:?}: {err}");
    }
}

#[test]
fn drape_bench_writes_the_peer_keys_and_npy() {
    let dir = tempfile::tempdir().unwrap();
    let result = dir.path().join("r.json");
    ok(&[
        "drape-bench",
        "--n",
        "12",
        "--out",
        dir.path().to_str().unwrap(),
        "--json",
        result.to_str().unwrap(),
    ]);
    let j = json(&result);
    for key in [
        "n",
        "t_sim_2s_wall_s",
        "verts_inside_sphere",
        "max_edge_stretch",
        "p99_edge_stretch",
        "drape_proxy",
        "lowest_z_m",
        "finite",
    ] {
        assert!(j.get(key).is_some(), "missing key {key} in {j}");
    }
    assert_eq!(j["verts_inside_sphere"], 0);
    let npy = std::fs::read(dir.path().join("final_n12.npy")).unwrap();
    assert!(npy.starts_with(b"\x93NUMPY"));
    assert!(npy.len() > 12 * 12 * 3 * 8);
}

#[test]
fn body_writes_obj_and_json_with_the_checked_keys() {
    let dir = tempfile::tempdir().unwrap();
    let obj = dir.path().join("body.obj");
    let report = dir.path().join("body.json");
    ok(&[
        "body",
        "--out",
        obj.to_str().unwrap(),
        "--json",
        report.to_str().unwrap(),
    ]);
    let j = json(&report);
    assert_eq!(j["boundary_edges"], 0);
    let vertices = j["vertices"].as_u64().unwrap();
    assert!(vertices > 10_000 && vertices <= 14_000);
    assert!(j["faces"].as_u64().unwrap() > 20_000);
    let h = j["height_m"].as_f64().unwrap();
    assert!((1.5..2.0).contains(&h), "height {h}");
    let text = std::fs::read_to_string(&obj).unwrap();
    assert_eq!(
        text.lines().filter(|l| l.starts_with("v ")).count() as u64,
        vertices
    );

    // A pose from a params file and from a motion frame.
    let params = dir.path().join("params.json");
    let mut pose = vec![0.0; 72];
    pose[18 * 3 + 1] = -1.2;
    std::fs::write(
        &params,
        serde_json::json!({"betas": [1.0], "pose": pose, "transl": [0.0, 1.0, 0.0]}).to_string(),
    )
    .unwrap();
    let r2 = dir.path().join("b2.json");
    ok(&[
        "body",
        "--params",
        params.to_str().unwrap(),
        "--json",
        r2.to_str().unwrap(),
    ]);
    let taller = json(&r2)["height_m"].as_f64().unwrap();
    assert!(
        (taller - h - 0.07).abs() < 0.01,
        "beta 0 is stature: {h} -> {taller}"
    );
    let r3 = dir.path().join("b3.json");
    ok(&[
        "body",
        "--motion",
        "squat",
        "--frame",
        "50",
        "--json",
        r3.to_str().unwrap(),
    ]);
    assert!(
        json(&r3)["posed_height_m"].as_f64().unwrap() < h - 0.3,
        "mid-squat is lower"
    );
}

#[test]
fn motions_list_json_has_the_required_motions() {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("list.json");
    ok(&["motions", "list", "--json", path.to_str().unwrap()]);
    let list = json(&path);
    let names: Vec<&str> = list
        .as_array()
        .unwrap()
        .iter()
        .map(|m| m["name"].as_str().unwrap())
        .collect();
    for required in [
        "walk",
        "run",
        "jumping_jacks",
        "arm_raise",
        "arm_swing",
        "squat",
        "torso_twist",
        "turn",
        "kick",
        "sway",
        "random",
        "random_legs",
    ] {
        assert!(
            names.contains(&required),
            "{required} missing from {names:?}"
        );
    }
    for m in list.as_array().unwrap() {
        assert_eq!(m["fps"], 30.0);
        assert!(m["frames"].as_u64().unwrap() > 0);
    }
}

#[test]
fn a_closed_output_pipe_ends_quietly_not_in_a_panic() {
    // As `dit-garment motions list | head -1` once did: the reader is gone before the first
    // line is written.
    for args in [
        &["motions", "list"][..],
        &["synth", "--example-spec", "tiny"],
    ] {
        let (reader, writer) = std::io::pipe().unwrap();
        drop(reader);
        let out = common::binary()
            .args(args)
            .stdout(writer)
            .stderr(std::process::Stdio::piped())
            .output()
            .unwrap();
        let stderr = String::from_utf8_lossy(&out.stderr);
        assert_eq!(out.status.code(), Some(0), "{args:?}: {stderr}");
        assert!(stderr.is_empty(), "{args:?}: {stderr}");
    }
}

#[test]
fn motions_show_and_export() {
    let dir = tempfile::tempdir().unwrap();
    let report = dir.path().join("show.json");
    ok(&[
        "motions",
        "show",
        "walk:speed=1.2,duration=3",
        "--json",
        report.to_str().unwrap(),
    ]);
    let j = json(&report);
    assert_eq!(j["frames"], 90);
    assert!(
        j["root_travel_m"][2].as_f64().unwrap() > 1.0,
        "walking moves forward along +z"
    );
    let seq = dir.path().join("kick.mcap");
    ok(&[
        "motions",
        "export",
        "kick:duration=1",
        "--out",
        seq.to_str().unwrap(),
        "--blend-frames",
        "10",
        "--settle-frames",
        "5",
        "--betas",
        "0.5,-1",
    ]);
    assert_eq!(topics(&seq)["/body/joints"], 45);
}

#[test]
fn bad_input_fails_with_a_clear_message_and_no_output() {
    let dir = tempfile::tempdir().unwrap();
    let obj = dir.path().join("x.obj");
    let err = fails(&[
        "body",
        "--body-model",
        "/no/such/SMPL.npz",
        "--out",
        obj.to_str().unwrap(),
    ]);
    assert!(err.contains("/no/such/SMPL.npz"), "{err}");
    let pkl = dir.path().join("SMPL_MALE.pkl");
    std::fs::write(&pkl, [0x80u8, 0x02, 0x7d]).unwrap();
    // `--model`, the flag's old name, still works where it means the body model.
    let err = fails(&[
        "body",
        "--model",
        pkl.to_str().unwrap(),
        "--out",
        obj.to_str().unwrap(),
    ]);
    assert!(err.contains("pickle") && err.contains("npz"), "{err}");
    let params = dir.path().join("p.json");
    std::fs::write(&params, r#"{"pose": [0.0, 1.0]}"#).unwrap();
    let err = fails(&[
        "body",
        "--params",
        params.to_str().unwrap(),
        "--out",
        obj.to_str().unwrap(),
    ]);
    assert!(err.contains("72"), "{err}");
    let err = fails(&["motions", "show", "moonwalk"]);
    assert!(
        err.contains("walk") && err.contains("sway"),
        "lists the motions: {err}"
    );
    let err = fails(&["motions", "show", "walk:speed=9"]);
    assert!(err.contains("speed"), "{err}");
    let broken = dir.path().join("broken.npz");
    std::fs::write(&broken, b"PK\x03\x04 truncated").unwrap();
    let seq = dir.path().join("out.mcap");
    let err = fails(&[
        "motions",
        "export",
        broken.to_str().unwrap(),
        "--out",
        seq.to_str().unwrap(),
    ]);
    assert!(err.contains("broken.npz"), "{err}");
    assert!(!obj.exists() && !seq.exists(), "nothing written on failure");
    assert_eq!(
        std::fs::read_dir(dir.path()).unwrap().count(),
        3,
        "only the three inputs remain: no outputs, no temporary files"
    );
}

/// The recording opens in the public Python `mcap` package (tests/readers/read_recording.py). Skipped
/// with a message where python3 with `mcap` and `numpy` is not installed (.ci/run installs
/// them).
#[test]
fn recording_reads_in_python() {
    if !common::python_has("cli::recording_reads_in_python", "mcap, numpy") {
        return;
    }
    let dir = tempfile::tempdir().unwrap();
    let seq = dir.path().join("seq.mcap");
    ok(&[
        "simulate",
        "--frames",
        "4",
        "--out",
        seq.to_str().unwrap(),
        "--quiet",
    ]);
    let j = common::python_tool("read_recording.py", &seq);
    assert_eq!(j["frames"], 4);
    assert_eq!(j["pose_dim"], 72);
}

#[test]
fn compare_scores_a_recording_against_itself_and_another() {
    let dir = tempfile::tempdir().unwrap();
    let (a, b) = (dir.path().join("a.mcap"), dir.path().join("b.mcap"));
    ok(&[
        "simulate",
        "--frames",
        "6",
        "--blend-frames",
        "3",
        "--settle-frames",
        "1",
        "--out",
        a.to_str().unwrap(),
        "--quiet",
    ]);
    ok(&[
        "simulate",
        "--frames",
        "6",
        "--blend-frames",
        "3",
        "--settle-frames",
        "1",
        "--material",
        "k_s=50",
        "--out",
        b.to_str().unwrap(),
        "--quiet",
    ]);
    let same = dir.path().join("same.json");
    ok(&[
        "compare",
        a.to_str().unwrap(),
        a.to_str().unwrap(),
        "--json",
        same.to_str().unwrap(),
    ]);
    let j = json(&same);
    for key in [
        "E_v",
        "E_CD",
        "E_CD_cm",
        "E_n",
        "E_c",
        "E_c_vertex",
        "E_b",
        "E_s",
        "E_d",
        "frames_scored",
    ] {
        assert!(j.get(key).is_some(), "missing {key}");
    }
    assert_eq!(j["frames_scored"], 2);
    for key in ["E_v", "E_CD", "E_n", "E_b", "E_s", "E_d"] {
        let v = j[key].as_f64().unwrap();
        assert!(v.abs() < 1e-12, "{key} of a recording against itself: {v}");
    }
    let other = dir.path().join("other.json");
    ok(&[
        "compare",
        a.to_str().unwrap(),
        b.to_str().unwrap(),
        "--json",
        other.to_str().unwrap(),
    ]);
    assert!(json(&other)["E_v"].as_f64().unwrap() > 0.0);
    let truncated = dir.path().join("cut.mcap");
    let bytes = std::fs::read(&a).unwrap();
    std::fs::write(&truncated, &bytes[..bytes.len() / 2]).unwrap();
    let err = fails(&["compare", a.to_str().unwrap(), truncated.to_str().unwrap()]);
    assert!(
        err.contains("cut.mcap") && err.contains("truncated"),
        "{err}"
    );
}

#[test]
fn regress_writes_the_checked_json() {
    // Two scenarios through the command (the suite itself runs scenario by scenario in
    // regress/tests/regression.rs).
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("regress.json");
    let text = ok(&[
        "regress",
        "--only",
        "hanging",
        "--json",
        out.to_str().unwrap(),
    ]);
    assert!(text.contains("3 of 3 scenarios pass"), "{text}");
    let j = json(&out);
    assert_eq!(j["long"], false);
    let scenarios = j["scenarios"].as_array().unwrap();
    let names: Vec<&str> = scenarios
        .iter()
        .map(|s| s["name"].as_str().unwrap())
        .collect();
    assert_eq!(
        names,
        [
            "hanging_chain_spring_stretch_relative_error",
            "hanging_sheet_segment_extension",
            "hanging_sheet_extension"
        ]
    );
    for s in scenarios {
        for key in ["name", "expected", "measured", "tolerance", "pass", "unit"] {
            assert!(s.get(key).is_some(), "missing {key} in {s}");
        }
        assert_eq!(s["pass"], true, "{s}");
    }
}

#[test]
fn regress_names_a_long_only_scenario_and_an_unknown_one() {
    let err = fails(&["regress", "--only", "soft_cloth"]);
    assert!(err.contains("run only with --long"), "{err}");
    let err = fails(&["regress", "--only", "no_such_scenario"]);
    assert!(
        err.contains("no scenario matches 'no_such_scenario'"),
        "{err}"
    );
}
