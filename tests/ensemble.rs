//! End-to-end: an ensemble folder (`ensemble.toml` naming two runs) predicts the mean of its
//! members where sampling is linear, and a bad ensemble file is named with nothing written.

mod common;

use std::path::Path;
use std::sync::OnceLock;

use common::{TinyRun, fails, ok, tiny_config, tiny_run};
use sim::recording::Recording;

fn s(p: &Path) -> &str {
    p.to_str().unwrap()
}

/// The tiny dataset, its tensors (32 x 32, lbs_residual) and a trained run, made once.
fn fixture() -> &'static TinyRun {
    static FIXTURE: OnceLock<TinyRun> = OnceLock::new();
    FIXTURE.get_or_init(|| tiny_run("ensemble-test", &[], &tiny_config("", "")))
}

/// The fixture's run trained again with seed 1, made once.
fn second_member() -> &'static Path {
    static SECOND: OnceLock<std::path::PathBuf> = OnceLock::new();
    SECOND.get_or_init(|| {
        let f = fixture();
        let other = f.dir.join("run-seed1");
        if !other.join("model.safetensors").exists() {
            let config = f.dir.join("m-seed1.toml");
            std::fs::write(&config, tiny_config("", "seed = 1\n")).unwrap();
            let tensors = f.dir.join("tensors");
            ok(&[
                "train",
                "--data",
                s(&tensors),
                "--out",
                s(&other),
                "--config",
                s(&config),
                "--threads",
                "1",
                "--quiet",
            ]);
        }
        other
    })
}

/// Writes `ensemble.toml` in `folder` naming `runs`.
fn name_members(folder: &Path, runs: &[&Path]) {
    let names: Vec<String> = runs.iter().map(|r| format!("{:?}", s(r))).collect();
    std::fs::write(
        folder.join("ensemble.toml"),
        format!("members = [{}]\n", names.join(", ")),
    )
    .unwrap();
}

/// `predict` of the fixture's truth with `model` into `out`, without guidance (sampling is
/// then linear in the network's output).
fn predict_args(model: &Path, out: &Path) -> Vec<String> {
    [
        "predict",
        "--model",
        s(model),
        "--config-from",
        s(&fixture().truth),
        "--out",
        s(out),
        "--guidance",
        "0",
        "--guidance-refine",
        "0",
        "--quiet",
    ]
    .map(String::from)
    .to_vec()
}

fn strs(args: &[String]) -> Vec<&str> {
    args.iter().map(|a| a.as_str()).collect()
}

/// An ensemble folder of two runs (the fixture's and one trained with another seed) predicts
/// the mean of their predictions where sampling is linear (no guidance).
#[test]
fn an_ensemble_predicts_the_mean_of_its_members() {
    let f = fixture();
    let other = second_member();
    let dir = tempfile::tempdir().unwrap();
    let ensemble = dir.path().join("pair");
    std::fs::create_dir_all(&ensemble).unwrap();
    let run = |model: &Path, name: &str| {
        let out = dir.path().join(name);
        ok(&strs(&predict_args(model, &out)));
        Recording::read(&out).unwrap().garment
    };
    name_members(&ensemble, &[&f.run, other]);
    let (a, b, pair) = (
        run(&f.run, "a.mcap"),
        run(other, "b.mcap"),
        run(&ensemble, "pair.mcap"),
    );
    let (mut apart, mut off) = (0.0f32, 0.0f32);
    for ((a, b), pair) in a
        .iter()
        .flatten()
        .zip(b.iter().flatten())
        .zip(pair.iter().flatten())
    {
        for k in 0..3 {
            apart = apart.max((a[k] - b[k]).abs());
            off = off.max((pair[k] - 0.5 * (a[k] + b[k])).abs());
        }
    }
    assert!(apart > 1e-4, "the two members predict alike ({apart} m)");
    assert!(
        off < 1e-5,
        "the ensemble is {off} m from the mean of its members"
    );
}

/// A bad ensemble file is named, with nothing written: too few members, members trained on
/// other tensors.
#[test]
fn a_bad_ensemble_is_named_and_nothing_written() {
    let f = fixture();
    let other = second_member();
    let dir = tempfile::tempdir().unwrap();
    let ensemble = dir.path().join("pair");
    std::fs::create_dir_all(&ensemble).unwrap();
    let out = dir.path().join("bad.mcap");
    let failure = || {
        let e = fails(&strs(&predict_args(&ensemble, &out)));
        assert!(!out.exists(), "{} was written", out.display());
        e
    };
    name_members(&ensemble, &[&f.run]);
    let e = failure();
    assert!(
        e.contains("ensemble.toml") && e.contains("at least 2"),
        "{e}"
    );
    let retrained = dir.path().join("other-tensors");
    std::fs::create_dir_all(&retrained).unwrap();
    for file in ["config.toml", "model.safetensors", "tensors.json"] {
        std::fs::copy(other.join(file), retrained.join(file)).unwrap();
    }
    let manifest = std::fs::read_to_string(retrained.join("tensors.json")).unwrap();
    std::fs::write(retrained.join("tensors.json"), format!("{manifest}\n")).unwrap();
    name_members(&ensemble, &[&f.run, &retrained]);
    let e = failure();
    assert!(
        e.contains("tensors.json") && e.contains("same tensors"),
        "{e}"
    );
}
