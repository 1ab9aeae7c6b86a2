//! End-to-end: a scene configuration saved with `--print-config`, run with `--config`, and
//! re-run from a recording with `--config-from` reproduces the flag run byte for byte; a bad
//! configuration file fails naming the file and the key, exit 1, nothing written.

mod common;

use std::path::Path;

use common::{ok, run_with};

/// A short scene with every kind of flag changed from its default.
const FLAGS: [&str; 18] = [
    "--motion",
    "walk:duration=0.3",
    "--frames",
    "6",
    "--blend-frames",
    "2",
    "--settle-frames",
    "1",
    "--substeps",
    "1",
    "--iterations",
    "4",
    "--betas",
    "0.3,-0.2",
    "--material",
    "k_s=120,k_b=2e-5",
    "--friction",
    "0.35",
];

fn simulate(extra: &[&str], out: &Path) {
    let out = out.to_str().unwrap();
    let args: Vec<&str> = ["simulate", "--quiet", "--out", out]
        .into_iter()
        .chain(extra.iter().copied())
        .collect();
    ok(&args);
}

fn bytes(path: &Path) -> Vec<u8> {
    std::fs::read(path).unwrap()
}

#[test]
fn print_config_config_and_config_from_reproduce_the_flag_run_bit_for_bit() {
    let dir = tempfile::tempdir().unwrap();
    let (flagged, configured, again) = (
        dir.path().join("flags.mcap"),
        dir.path().join("config.mcap"),
        dir.path().join("again.mcap"),
    );
    simulate(&FLAGS, &flagged);

    let mut print: Vec<&str> = vec!["simulate", "--print-config"];
    print.extend(FLAGS);
    let toml = ok(&print);
    assert!(toml.contains("[material]\nk_s_n_per_m = 120.0"), "{toml}");
    assert!(
        toml.contains("[solver]\nsubsteps = 1\nmax_iterations = 4"),
        "{toml}"
    );
    let config = dir.path().join("scene.toml");
    std::fs::write(&config, &toml).unwrap();
    simulate(&["--config", config.to_str().unwrap()], &configured);
    assert!(
        bytes(&flagged) == bytes(&configured),
        "--config of the printed configuration made different bytes"
    );

    simulate(&["--config-from", configured.to_str().unwrap()], &again);
    assert!(
        bytes(&configured) == bytes(&again),
        "--config-from made different bytes"
    );
    let recording = sim::recording::Recording::read(&again).unwrap();
    let carried = recording.meta.unwrap().scene_config().unwrap();
    assert_eq!(carried.to_toml(), toml);
    assert_eq!(recording.garment.len(), 6);

    // Flags override the file; a different value makes a different sequence.
    let shorter = dir.path().join("shorter.mcap");
    let config_path = config.to_str().unwrap();
    simulate(&["--config", config_path, "--frames", "4"], &shorter);
    assert_eq!(
        sim::recording::Recording::read(&shorter)
            .unwrap()
            .garment
            .len(),
        4
    );
    let printed = ok(&["demo", "--print-config", "--config", config_path]);
    assert_eq!(printed, toml, "demo resolves the same configuration");
}

/// Runs the binary expecting exit code 1; returns standard error.
fn exit_1(args: &[&str]) -> String {
    let out = run_with(args, &[]);
    let stderr = String::from_utf8_lossy(&out.stderr).to_string();
    assert_eq!(out.status.code(), Some(1), "{args:?}: {stderr}");
    stderr
}

#[test]
fn a_bad_configuration_names_the_file_and_key_and_writes_nothing() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("never.mcap");
    let out_dir = dir.path().join("demo");
    let cases = [
        ("unknown.toml", "[solver]\nsubstep = 3\n", "solver.substep"),
        ("top.toml", "garmnet = \"skirt\"\n", "garmnet"),
        (
            "range.toml",
            "[material]\nk_s_n_per_m = -3.0\n",
            "material.k_s_n_per_m = -3",
        ),
        (
            "zero.toml",
            "[solver]\nsubsteps = 0\n",
            "solver.substeps = 0",
        ),
        ("type.toml", "frames = \"ten\"\n", "type.toml"),
        ("syntax.toml", "frames = \n", "syntax.toml"),
    ];
    for (name, text, named) in cases {
        let path = dir.path().join(name);
        std::fs::write(&path, text).unwrap();
        let path = path.to_str().unwrap();
        let stderr = exit_1(&["simulate", "--config", path, "--out", out.to_str().unwrap()]);
        assert!(stderr.contains(named), "{name}: {stderr}");
        let stderr = exit_1(&["demo", "--config", path, "--out", out_dir.to_str().unwrap()]);
        assert!(stderr.contains(named), "demo {name}: {stderr}");
        let stderr = exit_1(&["simulate", "--config", path, "--print-config"]);
        assert!(stderr.contains(named), "--print-config {name}: {stderr}");
    }
    let stderr = exit_1(&["simulate", "--friction=-1", "--print-config"]);
    assert!(stderr.contains("friction = -1"), "{stderr}");
    let stderr = exit_1(&["simulate", "--material", "k_q=1", "--print-config"]);
    assert!(stderr.contains("k_q=1"), "{stderr}");
    assert!(
        !out.exists() && !out_dir.exists(),
        "a failed run wrote output"
    );
    let leftovers: Vec<_> = std::fs::read_dir(dir.path())
        .unwrap()
        .flatten()
        .filter(|e| !e.file_name().to_string_lossy().ends_with(".toml"))
        .collect();
    assert!(leftovers.is_empty(), "left behind: {leftovers:?}");
}
