//! Hostile and careless model folders (issue 54): weights of another dtype or not finite,
//! configurations and statistics that cannot be right, ensembles and odd files where a file
//! belongs. Every refusal is exit code 1 with a one-line error naming the file, tensor or key,
//! at load, before any work; nothing is written.

mod common;

use std::path::{Path, PathBuf};

use common::fails;
use serde_json::Value;

/// The shipped single network's run folder copied to `dir` with its first tensor spoiled by
/// `spoil` (`f64`: stored as F64; `nan`, `huge`: one value NaN or 1e30); returns the tensor's name.
fn spoiled_run(dir: &Path, spoil: &str) -> String {
    use safetensors::tensor::TensorView;
    let shipped = Path::new(env!("CARGO_MANIFEST_DIR")).join("surrogate/weights");
    std::fs::create_dir_all(dir).unwrap();
    for file in ["config.toml", "tensors.json"] {
        std::fs::copy(shipped.join(file), dir.join(file)).unwrap();
    }
    let bytes = std::fs::read(shipped.join("model.safetensors")).unwrap();
    let tensors = safetensors::SafeTensors::deserialize(&bytes).unwrap();
    let mut names = tensors.names();
    names.sort();
    let first = names[0].to_string();
    let mut owned: Vec<(String, safetensors::Dtype, Vec<usize>, Vec<u8>)> = Vec::new();
    for name in names {
        let view = tensors.tensor(name).unwrap();
        let mut values: Vec<f32> = view
            .data()
            .chunks_exact(4)
            .map(|b| f32::from_le_bytes([b[0], b[1], b[2], b[3]]))
            .collect();
        let (dtype, data) = match (name == first, spoil) {
            (true, "f64") => (
                safetensors::Dtype::F64,
                values
                    .iter()
                    .flat_map(|v| (*v as f64).to_le_bytes())
                    .collect(),
            ),
            (true, _) => {
                values[0] = if spoil == "nan" { f32::NAN } else { 1e30 };
                (
                    safetensors::Dtype::F32,
                    values.iter().flat_map(|v| v.to_le_bytes()).collect(),
                )
            }
            _ => (safetensors::Dtype::F32, view.data().to_vec()),
        };
        owned.push((name.to_string(), dtype, view.shape().to_vec(), data));
    }
    let views: Vec<(String, TensorView)> = owned
        .iter()
        .map(|(n, d, s, b)| (n.clone(), TensorView::new(*d, s.clone(), b).unwrap()))
        .collect();
    let out = safetensors::serialize(views, None).unwrap();
    std::fs::write(dir.join("model.safetensors"), out).unwrap();
    first
}

/// Weights of another dtype, or holding a NaN or an absurd value, are refused at load naming
/// the tensor, before any prediction (burn used to panic on F64, and NaN weights predicted
/// non-finite cloth).
#[test]
fn spoiled_weights_are_refused_at_load_naming_the_tensor() {
    let dir = tempfile::tempdir().unwrap();
    for (spoil, expected) in [
        ("f64", "is F64"),
        ("nan", "holds NaN"),
        ("huge", "holds 1000000000000000000000000000000"),
    ] {
        let run = dir.path().join(spoil);
        let tensor = spoiled_run(&run, spoil);
        let out = dir.path().join(format!("{spoil}.mcap"));
        let err = fails(&[
            "predict",
            "--model",
            run.to_str().unwrap(),
            "--out",
            out.to_str().unwrap(),
        ]);
        assert!(
            err.contains(&format!("tensor '{tensor}'")) && err.contains(expected),
            "{spoil}: {err}"
        );
        assert!(!out.exists());
    }
}

/// The shipped single network's run folder, whole, in `dir`.
fn shipped_copy(dir: &Path) -> PathBuf {
    let shipped = Path::new(env!("CARGO_MANIFEST_DIR")).join("surrogate/weights");
    std::fs::create_dir_all(dir).unwrap();
    for file in ["config.toml", "tensors.json", "model.safetensors"] {
        std::fs::copy(shipped.join(file), dir.join(file)).unwrap();
    }
    dir.to_path_buf()
}

/// `predict` with `model` into `out`, which must be refused: the error line.
fn predict_fails(model: &Path, out: &Path) -> String {
    fails(&[
        "predict",
        "--model",
        model.to_str().unwrap(),
        "--out",
        out.to_str().unwrap(),
    ])
}

/// Spoiled values of a run's `tensors.json`: (JSON pointer, the value, words of the error).
fn spoiled_tensors() -> Vec<(&'static str, Value, &'static str)> {
    vec![
        (
            "/normalization/targets/std/1",
            serde_json::json!(0.0),
            "normalization.targets.std[1] is 0",
        ),
        (
            "/normalization/conditions/std/0",
            serde_json::json!(-1.0),
            "normalization.conditions.std[0] is -1",
        ),
        (
            "/normalization/position_maps/std/2",
            serde_json::json!(1e300),
            "normalization.position_maps.std[2]",
        ),
        (
            "/normalization/targets/mean/0",
            serde_json::json!(1e308),
            "normalization.targets.mean[0]",
        ),
        (
            "/material_ranges/k_s",
            serde_json::json!([100.0, 100.0]),
            "material_ranges.k_s is [100, 100]",
        ),
        ("/format", serde_json::json!(99), "format 99"),
        (
            "/condition_layout/window",
            serde_json::json!(usize::MAX),
            "condition_layout.window is 18446744073709551615",
        ),
        (
            "/condition_layout/betas",
            serde_json::json!(11),
            "condition_layout makes 548 values, condition_dim says 547",
        ),
    ]
}

/// A model folder whose statistics, size or ensemble list cannot be right is refused at load,
/// naming the file and the value, before any prediction: `tensors.json` with a zero, negative
/// or huge deviation, a huge mean, an empty material range or an unknown format; a
/// `config.toml` of a network far larger than its weights (refused before it is built); an
/// ensemble naming one run twice. `evaluate` with nothing to score says so.
#[test]
fn model_folders_that_cannot_be_right_are_refused_at_load() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("p.mcap");
    let predict = |model: &Path| predict_fails(model, &out);
    for (k, (pointer, value, expected)) in spoiled_tensors().into_iter().enumerate() {
        let name = format!("spoiled{k}");
        let run = shipped_copy(&dir.path().join(&name));
        let path = run.join("tensors.json");
        let mut tensors: Value =
            serde_json::from_str(&std::fs::read_to_string(&path).unwrap()).unwrap();
        *tensors.pointer_mut(pointer).unwrap() = value;
        std::fs::write(&path, tensors.to_string()).unwrap();
        let err = predict(&run);
        assert!(
            err.contains("tensors.json") && err.contains(expected),
            "{name}: {err}"
        );
        assert!(!out.exists(), "{name}");
    }

    // A network four times wider than its weights: refused by counting, not by building it.
    let wide = shipped_copy(&dir.path().join("wide"));
    let config = std::fs::read_to_string(wide.join("config.toml")).unwrap();
    let config = config.replace("width = 128", "width = 512");
    assert!(config.contains("width = 512"));
    std::fs::write(wide.join("config.toml"), config).unwrap();
    let err = predict(&wide);
    assert!(
        err.contains("model.safetensors") && err.contains("does not fit") && err.contains("holds"),
        "{err}"
    );

    // One run twice in an ensemble, spelled two ways.
    let run = shipped_copy(&dir.path().join("member"));
    let ensemble = dir.path().join("twice");
    std::fs::create_dir_all(&ensemble).unwrap();
    std::fs::write(
        ensemble.join("ensemble.toml"),
        format!(
            "members = [\"../member\", \"{}\"]\n",
            run.join(".").display()
        ),
    )
    .unwrap();
    let err = predict(&ensemble);
    assert!(
        err.contains("members 1 and 2 are the same run folder"),
        "{err}"
    );

    let err = fails(&[
        "evaluate",
        "--model",
        "none",
        "--baselines",
        "",
        "--data",
        dir.path().join("data").to_str().unwrap(),
        "--json",
        dir.path().join("scores.json").to_str().unwrap(),
    ]);
    assert!(err.contains("nothing to score"), "{err}");
}

/// What sits where a model folder's files should be is named for what it is: a loop of links
/// at `model.safetensors` is not "missing", and an `ensemble.toml` that is a directory, a
/// FIFO or a link to `/dev/zero` is refused as that file, not blamed on a `config.toml`.
#[cfg(unix)]
#[test]
fn odd_files_in_a_model_folder_are_named_for_what_they_are() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("p.mcap");
    let predict = |model: &Path| predict_fails(model, &out);
    let looped = shipped_copy(&dir.path().join("looped"));
    let weights = looped.join("model.safetensors");
    std::fs::remove_file(&weights).unwrap();
    std::os::unix::fs::symlink(&weights, &weights).unwrap();
    let err = predict(&looped);
    assert!(
        err.contains("model.safetensors") && err.contains("loop"),
        "{err}"
    );

    for kind in ["dir", "fifo", "zero"] {
        let ensemble = dir.path().join(format!("ensemble_{kind}"));
        std::fs::create_dir_all(&ensemble).unwrap();
        let file = ensemble.join("ensemble.toml");
        match kind {
            "dir" => std::fs::create_dir(&file).unwrap(),
            "fifo" => {
                let made = std::process::Command::new("mkfifo").arg(&file).status();
                if !made.is_ok_and(|s| s.success()) {
                    continue;
                }
            }
            _ => std::os::unix::fs::symlink("/dev/zero", &file).unwrap(),
        }
        let err = predict(&ensemble);
        assert!(
            err.contains("ensemble.toml") && !err.contains("config.toml"),
            "{kind}: {err}"
        );
    }
}
