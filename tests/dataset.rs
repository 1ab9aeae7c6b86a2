//! End-to-end: dataset synthesis as users and schedulers run it: the tiny example spec,
//! SIGKILL at random moments then resume, shards (flags, Slurm and Kubernetes variables) and
//! merge, verify catching tampering, and bad specs.

mod common;

use std::collections::HashSet;
use std::path::{Path, PathBuf};
use std::process::Stdio;
use std::time::{Duration, Instant};

use common::{binary, fails, ok, run_with};
use serde_json::Value;

/// Eight 10-frame skirt sequences on a light solver: quick (about 0.15 s each), and long
/// enough to be killed mid-way.
const SMALL_SPEC: &str = r#"
name = "small"
seed = 5
[sequence]
frames = 10
blend_frames = 3
settle_frames = 1
shapes_per_motion = 2
draws_per_shape = 2
[solver]
substeps = 1
max_iterations = 6
[[garments]]
name = "skirt"
split = "train"
[[motions]]
source = "walk"
split = "train"
[[motions]]
source = "arm_swing"
split = "train"
"#;

/// `synth --spec SPEC --out OUT --quiet` and extra flags.
fn synth_args<'a>(spec: &'a str, out: &'a Path, extra: &[&'a str]) -> Vec<&'a str> {
    let mut args = vec![
        "synth",
        "--spec",
        spec,
        "--out",
        out.to_str().unwrap(),
        "--quiet",
    ];
    args.extend_from_slice(extra);
    args
}

fn write_spec(dir: &Path, text: &str) -> PathBuf {
    let path = dir.join("spec.toml");
    std::fs::write(&path, text).unwrap();
    path
}

fn manifest(dir: &Path) -> Vec<Value> {
    common::jsonl(&dir.join("manifest.jsonl"))
}

/// A manifest line without what legitimately differs between runs: timings (recordings
/// carry none, so their checksums and sizes are compared).
fn without_timings(mut v: Value) -> Value {
    let o = v.as_object_mut().unwrap();
    o.remove("wall_s");
    for a in o["attempts"].as_array_mut().unwrap() {
        a.as_object_mut().unwrap().remove("wall_s");
    }
    v
}

fn files_in(dir: &Path) -> Vec<String> {
    let mut names: Vec<String> = std::fs::read_dir(dir)
        .map(|e| {
            e.flatten()
                .map(|e| e.file_name().to_string_lossy().into_owned())
                .collect()
        })
        .unwrap_or_default();
    names.sort();
    names
}

#[test]
fn tiny_example_spec_synthesizes_verifies_and_reports_stats() {
    let dir = tempfile::tempdir().unwrap();
    let spec = ok(&["synth", "--example-spec", "tiny"]);
    assert!(
        spec.contains("[[garments]]") && spec.contains("# "),
        "commented TOML"
    );
    let spec_path = write_spec(dir.path(), &spec);
    let out = dir.path().join("tiny");
    let report = dir.path().join("synth.json");
    ok(&synth_args(
        spec_path.to_str().unwrap(),
        &out,
        &["--json", report.to_str().unwrap()],
    ));
    ok(&["dataset", "verify", out.to_str().unwrap()]);
    let stats_path = dir.path().join("stats.json");
    ok(&[
        "dataset",
        "stats",
        out.to_str().unwrap(),
        "--json",
        stats_path.to_str().unwrap(),
    ]);
    let stats: Value =
        serde_json::from_str(&std::fs::read_to_string(&stats_path).unwrap()).unwrap();
    assert_eq!(stats["sequences"], 4);
    assert_eq!(stats["frames"], 4 * 30);
    let lines = manifest(&out);
    let failed = lines.iter().filter(|l| l["status"] == "failed").count();
    assert_eq!(stats["failed"], failed, "stats against the manifest");
    assert_eq!(failed, 0, "the tiny spec passes its gates: {lines:?}");
    for split in ["train", "test", "test_garment", "test_motion"] {
        assert_eq!(stats["splits"][split], 1, "{split}: {}", stats["splits"]);
    }
    for line in &lines {
        for key in [
            "id", "split", "garment", "motion", "betas", "material", "seed", "frames", "status",
            "attempts", "file", "sha256", "software", "wall_s",
        ] {
            assert!(line.get(key).is_some(), "manifest line lacks {key}");
        }
        assert!(line["material"]["k_s_n_per_m"].is_number());
        if line["status"] == "failed" {
            assert!(line["reason"].as_str().is_some_and(|r| !r.is_empty()));
        }
    }
    assert!(
        out.join("templates/skirt.obj").exists() && out.join("templates/tank_tight.obj").exists()
    );
    // A sequence replaced by a link to an endless device is reported, not read forever.
    let file = lines[0]["file"].as_str().unwrap();
    std::fs::remove_file(out.join(file)).unwrap();
    std::os::unix::fs::symlink("/dev/zero", out.join(file)).unwrap();
    let verified = run_with(&["dataset", "verify", out.to_str().unwrap()], &[]);
    let said = format!(
        "{}{}",
        String::from_utf8_lossy(&verified.stdout),
        String::from_utf8_lossy(&verified.stderr)
    );
    assert_eq!(verified.status.code(), Some(1), "{said}");
    assert!(said.contains("character device"), "{said}");
    let paper = ok(&["synth", "--example-spec", "paper"]);
    assert!(paper.contains("paper-like"));
    assert_eq!(
        ok(&["synth", "--example-spec"]),
        spec,
        "tiny is the default example"
    );
}

#[test]
fn killed_runs_resume_without_losing_or_duplicating_and_match_an_uninterrupted_run() {
    let dir = tempfile::tempdir().unwrap();
    let spec = write_spec(dir.path(), SMALL_SPEC);
    let clean = dir.path().join("clean");
    ok(&synth_args(spec.to_str().unwrap(), &clean, &[]));
    let reference = manifest(&clean);
    assert_eq!(reference.len(), 8);
    let killed = dir.path().join("killed");
    let seed = kill_repeatedly(&spec, &killed);
    let last = ok(&synth_args(spec.to_str().unwrap(), &killed, &[]));
    eprintln!("{last}");
    ok(&["dataset", "verify", killed.to_str().unwrap()]);
    let resumed = manifest(&killed);
    let ids: HashSet<&str> = resumed.iter().map(|l| l["id"].as_str().unwrap()).collect();
    assert_eq!(ids.len(), resumed.len(), "no sequence twice");
    assert_eq!(
        resumed.into_iter().map(without_timings).collect::<Vec<_>>(),
        reference
            .into_iter()
            .map(without_timings)
            .collect::<Vec<_>>(),
        "same spec, same manifest except timings (kill seed {seed})"
    );
    let sequences = files_in(&killed.join("sequences"));
    assert_eq!(sequences.len(), 8, "{sequences:?}");
    assert!(
        sequences.iter().all(|n| n.ends_with(".mcap")),
        "{sequences:?}"
    );
    for name in &sequences {
        let read = |d: &Path| std::fs::read(d.join("sequences").join(name)).unwrap();
        assert!(
            read(&killed) == read(&clean),
            "{name}: the resumed recording differs from the uninterrupted run's (kill seed {seed})"
        );
    }
    assert!(
        files_in(&killed.join("records"))
            .iter()
            .all(|n| n.ends_with(".json"))
    );

    // A re-run of a finished dataset simulates nothing.
    let again = ok(&synth_args(spec.to_str().unwrap(), &killed, &[]));
    assert!(again.contains("8 already done"), "{again}");

    // Verify catches a damaged recording; a re-run redoes exactly that sequence.
    let victim = killed.join("sequences").join(&sequences[3]);
    let mut bytes = std::fs::read(&victim).unwrap();
    let middle = bytes.len() / 2;
    bytes[middle] ^= 0xff;
    std::fs::write(&victim, bytes).unwrap();
    let err = fails(&["dataset", "verify", killed.to_str().unwrap()]);
    assert!(err.contains("checksum"), "{err}");
    let redo = ok(&synth_args(spec.to_str().unwrap(), &killed, &[]));
    assert!(redo.contains("7 already done"), "{redo}");
    ok(&["dataset", "verify", killed.to_str().unwrap()]);
}

/// Kills synthesis into `killed` at random moments: the first while the template is made, the
/// others after a given number of sequences have finished plus a random delay, so they land
/// while recordings and records are being written. The moments come from a seed, printed
/// (and returned, for every failure's message) so a failure can be replayed with
/// DIT_GARMENT_KILL_SEED.
fn kill_repeatedly(spec: &Path, killed: &Path) -> u64 {
    let seed: u64 = match std::env::var("DIT_GARMENT_KILL_SEED") {
        Ok(s) => s.parse().expect("DIT_GARMENT_KILL_SEED is a number"),
        Err(_) => std::time::SystemTime::now()
            .duration_since(std::time::UNIX_EPOCH)
            .unwrap()
            .subsec_nanos() as u64,
    };
    eprintln!("kill seed {seed} (replay: DIT_GARMENT_KILL_SEED={seed})");
    let mut state = seed | 1;
    let mut random_ms = |range: u64| {
        state = state
            .wrapping_mul(6364136223846793005)
            .wrapping_add(1442695040888963407);
        (state >> 33) % range
    };
    let records = |d: &Path| {
        files_in(&d.join("records"))
            .iter()
            .filter(|n| n.ends_with(".json"))
            .count()
    };
    let mut partial_runs = 0;
    for finished_before_kill in [0usize, 1, 3, 5, 6] {
        let before = records(killed);
        let mut child = binary()
            .args(synth_args(spec.to_str().unwrap(), killed, &[]))
            .stdout(Stdio::null())
            .stderr(Stdio::null())
            .spawn()
            .unwrap();
        let started = Instant::now();
        while records(killed) < finished_before_kill
            && child.try_wait().unwrap().is_none()
            && started.elapsed() < Duration::from_secs(120)
        {
            std::thread::sleep(Duration::from_millis(5));
        }
        let delay = Duration::from_millis(random_ms(if finished_before_kill == 0 {
            2500
        } else {
            400
        }));
        std::thread::sleep(delay);
        let _ = child.kill(); // SIGKILL
        let _ = child.wait();
        let after = records(killed);
        eprintln!(
            "kill after {finished_before_kill} records + {delay:?}: records {before} -> {after}"
        );
        if after > before && after < 8 {
            partial_runs += 1;
        }
    }
    assert!(
        partial_runs >= 1,
        "no kill landed in the middle of the simulations (kill seed {seed})"
    );
    seed
}

#[test]
fn shards_from_flags_slurm_and_kubernetes_merge_into_one_dataset() {
    let dir = tempfile::tempdir().unwrap();
    let spec = write_spec(dir.path(), SMALL_SPEC);
    let s = spec.to_str().unwrap();
    // Slurm array 3..=4 (two tasks) into one shared folder: the last task writes the manifest.
    let shared = dir.path().join("shared");
    for id in ["3", "4"] {
        let out = run_with(
            &synth_args(s, &shared, &[]),
            &[
                ("SLURM_ARRAY_TASK_ID", id),
                ("SLURM_ARRAY_TASK_COUNT", "2"),
                ("SLURM_ARRAY_TASK_MIN", "3"),
            ],
        );
        assert!(
            out.status.success(),
            "{}",
            String::from_utf8_lossy(&out.stderr)
        );
        let text = String::from_utf8_lossy(&out.stdout);
        assert!(
            text.contains(&format!("shard {}/2 has 4", id.parse::<u32>().unwrap() - 3)),
            "{text}"
        );
    }
    ok(&["dataset", "verify", shared.to_str().unwrap()]);

    // Kubernetes indexed job into separate folders, then merge; the count must be given.
    let (a, b) = (dir.path().join("k0"), dir.path().join("k1"));
    for (index, out) in [("0", &a), ("1", &b)] {
        let o = run_with(
            &synth_args(s, out, &["--shard-count", "2"]),
            &[("JOB_COMPLETION_INDEX", index)],
        );
        assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    }
    assert!(
        !a.join("manifest.jsonl").exists(),
        "a lone shard writes no manifest"
    );
    let err = fails(&["dataset", "verify", a.to_str().unwrap()]);
    assert!(err.contains("manifest"), "{err}");
    let err = fails(&[
        "dataset",
        "merge",
        dir.path().join("partial").to_str().unwrap(),
        a.to_str().unwrap(),
    ]);
    assert!(err.contains("no finished record"), "{err}");
    let merged = dir.path().join("merged");
    ok(&[
        "dataset",
        "merge",
        merged.to_str().unwrap(),
        a.to_str().unwrap(),
        b.to_str().unwrap(),
    ]);
    ok(&["dataset", "verify", merged.to_str().unwrap()]);
    assert_eq!(manifest(&merged).len(), 8);
    let ids = |d: &Path| {
        manifest(d)
            .iter()
            .map(|l| l["id"].clone())
            .collect::<Vec<_>>()
    };
    assert_eq!(
        ids(&merged),
        ids(&shared),
        "same sequences whichever way it was sharded"
    );

    let o = run_with(
        &["synth", "--spec", s, "--out", a.to_str().unwrap()],
        &[("JOB_COMPLETION_INDEX", "0")],
    );
    assert!(!o.status.success());
    assert!(String::from_utf8_lossy(&o.stderr).contains("--shard-count"));
    assert!(fails(&synth_args(s, &a, &["--shard", "2/2"])).contains("out of range"));
}

#[test]
fn bad_specs_get_errors_naming_the_key() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("out");
    let cases = [
        (SMALL_SPEC.replace("frames = 10", "framez = 10"), "framez"),
        (
            format!("{SMALL_SPEC}\n[material]\nk_s = [-1.0, 5.0]\n"),
            "material.k_s",
        ),
        (SMALL_SPEC.replace("seed = 5", "seed = \"five\""), "seed"),
        (
            SMALL_SPEC.replace(
                "split = \"train\"\n[[motions]]",
                "split = \"validation\"\n[[motions]]",
            ),
            "validation",
        ),
        (
            SMALL_SPEC.replace("name = \"skirt\"", "name = \"no_such_garment\""),
            "no_such_garment",
        ),
        (
            SMALL_SPEC.replace("source = \"walk\"", "source = \"moonwalk\""),
            "moonwalk",
        ),
        (
            SMALL_SPEC.replace("name = \"skirt\"", "name = \"skirt\"\nvariants = 2"),
            "only a library design has variants",
        ),
    ];
    for (text, key) in cases {
        // A folder that exists already (a user's, with a file of theirs) is left as it was.
        std::fs::create_dir_all(&out).unwrap();
        std::fs::write(out.join("notes.txt"), "mine").unwrap();
        let spec = write_spec(dir.path(), &text);
        let err = fails(&synth_args(spec.to_str().unwrap(), &out, &[]));
        assert!(err.contains(key), "error should name {key}: {err}");
        assert_eq!(
            files_in(&out),
            ["notes.txt"],
            "a refused spec ({key}) wrote into --out"
        );
        let _ = std::fs::remove_dir_all(&out);
    }
    let missing = fails(&synth_args("/no/such/spec.toml", &out, &[]));
    assert!(missing.contains("/no/such/spec.toml"), "{missing}");
}
