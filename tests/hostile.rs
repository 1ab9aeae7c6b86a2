//! Hostile and careless input (issue 27): every refusal is exit code 1 with a one-line error
//! naming the file, flag or key; never a panic, an abort, a hang or a clobbered file; nothing
//! at `--out` and no `*.tmp` beside it after a refusal or a signal. Each case failed on the
//! main branch before these checks.

mod common;

use std::path::{Path, PathBuf};
use std::process::Stdio;
use std::time::Duration;

use common::{binary, fails, ok};
use serde_json::Value;

/// A short simulation of the default garment: a real recording to damage.
fn recording(dir: &Path) -> PathBuf {
    let path = dir.join("ok.mcap");
    ok(&[
        "simulate",
        "--quiet",
        "--frames",
        "4",
        "--blend-frames",
        "2",
        "--settle-frames",
        "1",
        "--out",
        path.to_str().unwrap(),
    ]);
    path
}

/// Byte ranges of the top-level chunk records of an MCAP file.
fn chunks(bytes: &[u8]) -> Vec<std::ops::Range<usize>> {
    let mut at = 8;
    let mut out = Vec::new();
    while at + 9 <= bytes.len() - 8 {
        let len = u64::from_le_bytes(bytes[at + 1..at + 9].try_into().unwrap()) as usize;
        if bytes[at] == 0x06 {
            out.push(at..at + 9 + len);
        }
        at += 9 + len;
    }
    out
}

/// `garments check OBJ` (refused: its report) and `simulate --garment OBJ` (refused: its
/// error), with nothing written.
fn check_and_simulate(obj: &Path) -> (String, String) {
    let checked = common::run_with(&["garments", "check", obj.to_str().unwrap()], &[]);
    let report = String::from_utf8_lossy(&checked.stdout).to_string();
    assert_eq!(checked.status.code(), Some(1), "{report}");
    let out = obj.with_extension("mcap");
    let err = fails(&[
        "simulate",
        "--garment",
        obj.to_str().unwrap(),
        "--out",
        out.to_str().unwrap(),
    ]);
    assert!(!out.exists());
    (report, err)
}

/// Every file in `dir` whose name ends with `.tmp`.
fn temporaries(dir: &Path) -> Vec<String> {
    std::fs::read_dir(dir)
        .unwrap()
        .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
        .filter(|n| n.ends_with(".tmp"))
        .collect()
}

#[test]
fn a_damaged_recording_is_reported_by_every_reader_with_its_chunk() {
    let dir = tempfile::tempdir().unwrap();
    let good = recording(dir.path());
    let mut bytes = std::fs::read(&good).unwrap();
    let first = chunks(&bytes)[0].clone();
    let middle = (first.start + first.end) / 2;
    for b in &mut bytes[middle..middle + 64] {
        *b ^= 0x5a;
    }
    let bad = dir.path().join("bad.mcap");
    std::fs::write(&bad, &bytes).unwrap();
    let bad = bad.to_str().unwrap();
    let pictures = dir.path().join("pictures");
    let page = dir.path().join("view.html");
    for args in [
        vec!["render", bad, "--out", pictures.to_str().unwrap()],
        vec!["view", bad, "--out", page.to_str().unwrap()],
        vec!["compare", good.to_str().unwrap(), bad],
        vec!["uv", bad, "--out", pictures.to_str().unwrap()],
    ] {
        let err = fails(&args);
        assert!(
            err.contains("bad.mcap") && err.contains("chunk 0 of") && err.contains("CRC"),
            "{args:?}: {err}"
        );
    }
    assert!(!page.exists());
}

#[test]
fn numbers_that_would_exhaust_memory_are_refused_by_name_before_work() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("x.mcap");
    let out = out.to_str().unwrap();
    for (flag, value, key) in [
        ("--blend-frames", "99999999", "blend_frames"),
        ("--settle-frames", "4000000000", "settle_frames"),
        ("--frames", "900000000", "frames"),
    ] {
        let err = fails(&["simulate", flag, value, "--out", out]);
        assert!(err.contains(key) && err.contains(value), "{flag}: {err}");
    }
    let err = fails(&[
        "motions",
        "export",
        "walk",
        "--blend-frames",
        "99999999",
        "--out",
        out,
    ]);
    assert!(
        err.contains("--blend-frames 99999999") && err.contains("108000"),
        "{err}"
    );
    let err = fails(&[
        "drape-bench",
        "--n",
        "100000",
        "--out",
        dir.path().to_str().unwrap(),
    ]);
    assert!(err.contains("--n 100000") && err.contains("512"), "{err}");
    for (args, named) in [
        (vec!["--betas", "1e300"], "betas[0]"),
        (
            vec!["--self-contact-distance", "10"],
            "self_contact_distance",
        ),
        (
            vec!["--substeps", "4096", "--iterations", "4096"],
            "max_iterations",
        ),
    ] {
        let mut all = vec!["simulate", "--out", out];
        all.extend(args);
        let err = fails(&all);
        assert!(err.contains(named), "{named}: {err}");
    }
    let pictures = dir.path().join("pictures");
    let pictures = pictures.to_str().unwrap();
    for (flag, value) in [("--gif-size", "100000"), ("--size", "8192")] {
        let err = fails(&["render", "no.mcap", flag, value, "--out", pictures]);
        assert!(err.contains(flag) && err.contains(value), "{flag}: {err}");
    }
    let data = dir.path().join("data");
    let data = data.to_str().unwrap();
    for (flag, value) in [
        ("--window", "1000000000"),
        ("--shard-frames", "0"),
        ("--resolution", "100000"),
    ] {
        let err = fails(&["dataset", "tensors", data, "--out", pictures, flag, value]);
        assert!(err.contains(&format!("{flag} {value}")), "{flag}: {err}");
    }
    let err = fails(&[
        "synth", "--spec", "no.toml", "--out", data, "--jobs", "100000",
    ]);
    assert!(err.contains("--jobs 100000"), "{err}");
    let err = fails(&["predict", "--out", out, "--threads", "100000"]);
    assert!(err.contains("--threads 100000"), "{err}");
    assert!(!Path::new(out).exists());
    assert!(temporaries(dir.path()).is_empty());
}

#[test]
fn a_spec_whose_plan_would_exhaust_memory_is_refused_before_the_folder_is_touched() {
    let dir = tempfile::tempdir().unwrap();
    let tiny = ok(&["synth", "--example-spec", "tiny"]);
    let out = dir.path().join("data");
    for (from, to, key) in [
        (
            "shapes_per_motion = 1",
            "shapes_per_motion = 100000000",
            "shapes_per_motion",
        ),
        (
            "draws_per_shape = 1",
            "draws_per_shape = 100000000",
            "draws_per_shape",
        ),
        ("test = 1 ", "test = 100000000 ", "splits.test"),
        ("retries = 1", "retries = 1000000", "gates.retries"),
        ("timeout_s = 900.0", "timeout_s = 1e300", "gates.timeout_s"),
        (
            "blend_frames = 10",
            "blend_frames = 99999999",
            "sequence.blend_frames",
        ),
    ] {
        assert!(tiny.contains(from), "{from}");
        let spec = dir.path().join("spec.toml");
        std::fs::write(&spec, tiny.replacen(from, to, 1)).unwrap();
        let err = fails(&[
            "synth",
            "--spec",
            spec.to_str().unwrap(),
            "--out",
            out.to_str().unwrap(),
        ]);
        assert!(
            err.contains("spec.toml") && err.contains(key),
            "{key}: {err}"
        );
        assert!(!out.exists(), "{key}: the dataset folder was created");
    }
}

/// A library design's sewing pattern, changed by `edit`, written to `name`.
fn pattern(dir: &Path, name: &str, edit: impl Fn(&mut Value)) -> PathBuf {
    let source = dir.join("source.json");
    if !source.exists() {
        ok(&[
            "garments",
            "show",
            "tank_tight",
            "--pattern-out",
            source.to_str().unwrap(),
        ]);
    }
    let mut spec: Value = serde_json::from_str(&std::fs::read_to_string(&source).unwrap()).unwrap();
    edit(&mut spec);
    let path = dir.join(name);
    std::fs::write(&path, serde_json::to_string(&spec).unwrap()).unwrap();
    path
}

#[test]
fn patterns_that_would_mesh_forever_are_refused() {
    let dir = tempfile::tempdir().unwrap();
    let curved = pattern(dir.path(), "curved_specification.json", |spec| {
        // Edge 1 of the back (the armhole) is stitched to nothing, so no seam check sees it.
        let edges = &mut spec["pattern"]["panels"]["back"]["edges"];
        edges[1]["curvature"] = serde_json::json!([0.5, 1e12]);
    });
    let huge = pattern(dir.path(), "huge_specification.json", |spec| {
        for panel in spec["pattern"]["panels"]
            .as_object_mut()
            .unwrap()
            .values_mut()
        {
            for v in panel["vertices"].as_array_mut().unwrap() {
                for c in v.as_array_mut().unwrap() {
                    *c = Value::from(c.as_f64().unwrap() * 1e6);
                }
            }
        }
    });
    for file in [&curved, &huge] {
        let err = fails(&["garments", "check", file.to_str().unwrap()]);
        let name = file.file_name().unwrap().to_str().unwrap();
        assert!(
            err.contains(name) && err.contains("vertices, more than 100000"),
            "{err}"
        );
    }
    let obj = dir.path().join("t.obj");
    let err = fails(&[
        "garments",
        "make",
        "tank_tight",
        "--edge-length",
        "0.00001",
        "--out",
        obj.to_str().unwrap(),
    ]);
    assert!(err.contains("edge length is too small"), "{err}");
    assert!(!obj.exists());
}

#[test]
fn a_fan_of_a_huge_polygon_is_refused_and_a_byte_order_mark_is_read() {
    let dir = tempfile::tempdir().unwrap();
    // One 3,000-sided polygon: its fan puts every triangle at vertex 1.
    let n = 3000;
    let mut text = String::new();
    for k in 0..n {
        let a = k as f64 / n as f64 * std::f64::consts::TAU;
        text += &format!(
            "v {} {} 0\nvt {} {}\n",
            0.3 * a.cos(),
            0.3 * a.sin(),
            0.5,
            0.5
        );
    }
    text += "f";
    for k in 1..=n {
        text += &format!(" {k}/{k}");
    }
    text += "\n";
    let fan = dir.path().join("fan.obj");
    std::fs::write(&fan, text).unwrap();
    let (report, err) = check_and_simulate(&fan);
    assert!(
        report.contains("vertices in too many triangles: 1"),
        "{report}"
    );
    assert!(err.contains("too many triangles"), "{err}");
    // A byte-order mark before the first line is not part of it.
    let bom = dir.path().join("bom.obj");
    let quad = "v 0 0 0\nv 0.3 0 0\nv 0.3 0.3 0\nv 0 0.3 0\nvt 0 0\nvt 1 0\nvt 1 1\nvt 0 1\n\
                f 1/1 2/2 3/3\nf 1/1 3/3 4/4\n";
    std::fs::write(&bom, format!("\u{feff}{quad}")).unwrap();
    let json = dir.path().join("bom.json");
    ok(&[
        "garments",
        "check",
        bom.to_str().unwrap(),
        "--json",
        json.to_str().unwrap(),
    ]);
    assert_eq!(common::json(&json)["vertices"], 4);
}

#[test]
fn outputs_that_are_not_regular_files_are_refused_before_the_run() {
    let dir = tempfile::tempdir().unwrap();
    let target = dir.path().join("target.mcap");
    std::fs::write(&target, "keep me").unwrap();
    let link = dir.path().join("link.mcap");
    std::os::unix::fs::symlink(&target, &link).unwrap();
    let folder = dir.path().join("folder");
    std::fs::create_dir(&folder).unwrap();
    for (out, kind) in [
        (link.as_path(), "symbolic link"),
        (folder.as_path(), "directory"),
        (Path::new("/dev/null"), "character device"),
    ] {
        // A long run: a refusal after it would take minutes, not a moment.
        let err = fails(&[
            "simulate",
            "--frames",
            "100000",
            "--out",
            out.to_str().unwrap(),
        ]);
        assert!(
            err.contains(kind) && err.contains("refusing to replace"),
            "{err}"
        );
    }
    assert_eq!(std::fs::read_to_string(&target).unwrap(), "keep me");
    // A folder output must not be a file.
    let err = fails(&["render", "no.mcap", "--out", target.to_str().unwrap()]);
    assert!(
        err.contains("target.mcap") && err.contains("regular file"),
        "{err}"
    );
    assert!(temporaries(dir.path()).is_empty());
}

#[test]
fn a_signal_removes_the_outputs_being_written() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("long.mcap");
    for signal in ["INT", "TERM", "HUP"] {
        let mut child = binary()
            .args(["simulate", "--quiet", "--frames", "300", "--out"])
            .arg(&out)
            .stderr(Stdio::piped())
            .spawn()
            .unwrap();
        // Wait until the recording is being written, then stop the run.
        let started = std::time::Instant::now();
        while temporaries(dir.path()).is_empty() {
            assert!(
                started.elapsed() < Duration::from_secs(120),
                "no temporary appeared"
            );
            std::thread::sleep(Duration::from_millis(20));
        }
        let sent = std::process::Command::new("kill")
            .args([&format!("-{signal}"), &child.id().to_string()])
            .status()
            .unwrap();
        assert!(sent.success());
        let status = child.wait().unwrap();
        assert_eq!(status.code(), Some(130), "SIG{signal}: {status:?}");
        assert!(!out.exists(), "SIG{signal}: a final output appeared");
        assert!(
            temporaries(dir.path()).is_empty(),
            "SIG{signal}: temporaries left"
        );
    }
}

/// A NaN on the file's vertex 11 is reported as OBJ vertex 11, though the reader orders
/// vertices by group and first use (here the second group is used first).
#[test]
fn mesh_errors_name_vertices_as_the_file_numbers_them() {
    let dir = tempfile::tempdir().unwrap();
    let mut text = String::new();
    for k in 0..12 {
        let (x, y) = ((k % 4) as f64 * 0.1, (k / 4) as f64 * 0.1);
        if k == 10 {
            text += "v nan 0.1 0\n";
        } else {
            text += &format!("v {x} {y} 0\n");
        }
        text += &format!("vt {} {}\n", x, y);
    }
    // Group b (rows 1-2) comes first in the file, group a (rows 0-1) second.
    text += "g b\nf 5/5 6/6 10/10\nf 6/6 11/11 10/10\ng a\nf 1/1 2/2 5/5\nf 2/2 6/6 5/5\n";
    let obj = dir.path().join("nan.obj");
    std::fs::write(&obj, text).unwrap();
    let (report, err) = check_and_simulate(&obj);
    assert!(
        report.contains("non-finite positions: 1 (e.g. OBJ vertex 11)"),
        "{report}"
    );
    assert!(
        err.contains("OBJ vertex 11") && err.contains("nan.obj"),
        "{err}"
    );
}

/// Two outputs of one command may not be one file, and evaluate never writes into the dataset
/// it reads: both refused before any work, naming the paths.
#[test]
fn outputs_over_outputs_or_inputs_are_refused() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("x.mcap");
    let same = dir.path().join("sub/../x.mcap");
    std::fs::create_dir(dir.path().join("sub")).unwrap();
    let err = fails(&[
        "simulate",
        "--frames",
        "100000",
        "--out",
        out.to_str().unwrap(),
        "--json",
        same.to_str().unwrap(),
    ]);
    assert!(
        err.contains("two outputs of one command name one file"),
        "{err}"
    );
    assert!(!out.exists());
    let data = dir.path().join("data");
    std::fs::create_dir(&data).unwrap();
    std::fs::write(data.join("manifest.jsonl"), "").unwrap();
    for (flag, path) in [
        ("--json", data.join("manifest.jsonl")),
        ("--report", data.clone()),
    ] {
        let err = fails(&[
            "evaluate",
            "--model",
            "none",
            "--data",
            data.to_str().unwrap(),
            flag,
            path.to_str().unwrap(),
        ]);
        assert!(err.contains("inside the dataset folder"), "{flag}: {err}");
    }
    assert_eq!(
        std::fs::read_to_string(data.join("manifest.jsonl")).unwrap(),
        ""
    );
}

/// Flags' own mistakes are blamed on the flag, not on the dataset or model they point at.
#[test]
fn empty_and_zero_flags_are_named() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("x.json");
    let out = out.to_str().unwrap();
    for (flags, expected) in [
        (vec!["--max-sequences", "0"], "--max-sequences 0"),
        (vec!["--splits", ""], "--splits holds an empty name"),
    ] {
        let mut args = vec![
            "evaluate",
            "--model",
            "none",
            "--data",
            "/no/such/data",
            "--json",
            out,
        ];
        args.extend(flags);
        let err = fails(&args);
        assert!(err.contains(expected), "{err}");
    }
    let err = fails(&[
        "evaluate", "--model", "", "--data", "/no/such", "--json", out,
    ]);
    assert!(err.contains("--model = \"\": empty"), "{err}");
    let err = fails(&["motions", "show", "random:seed=18446744073709551616"]);
    assert!(err.contains("from 0 to 18446744073709551615"), "{err}");
}

/// Material values past the engine's bounds are refused by every command that takes them,
/// before any work: `predict` no longer turns k_s = 1e300 into non-finite vertices.
#[test]
fn material_values_past_their_bounds_are_refused_by_simulate_and_predict() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("x.mcap");
    let out = out.to_str().unwrap();
    for material in ["k_s=1e300", "rho=1e9", "k_b=1e-300"] {
        for command in [
            vec!["simulate", "--material", material, "--out", out],
            vec![
                "predict",
                "--model",
                "builtin-single",
                "--material",
                material,
                "--out",
                out,
            ],
        ] {
            let err = fails(&command);
            assert!(
                err.contains("material.") && err.contains("must be a number of"),
                "{command:?}: {err}"
            );
        }
    }
    assert!(!Path::new(out).exists());
}
