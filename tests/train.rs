//! End-to-end: `train` as a user runs it on tensors of a small synthesized dataset: every
//! output with its keys; the NumPy reference reproduces the model's output (and catches a
//! wrong configuration); a run killed mid-way and resumed logs the uninterrupted run's values;
//! bad configurations and damaged or mismatched checkpoints are named, with exit 1.

mod common;

use std::path::{Path, PathBuf};
use std::sync::OnceLock;
use std::time::{Duration, Instant};

use common::{binary, fails, json, ok, python_has, run_with, tiny_tensors};
use serde_json::Value;

/// A tiny model and a short schedule: checkpoints every 10 steps; dropout on, so that a resumed
/// run must draw the uninterrupted run's masks.
const CONFIG: &str = r#"
[model]
patch = 4
width = 16
depth = 1
heads = 2
mlp_ratio = 2.0
condition_tokens = 2
[training]
steps = 60
batch = 2
lr = 1e-3
warmup_steps = 5
log_every = 5
val_every = 10
checkpoint_every = 10
val_frames = 4
dropout = 0.1
"#;

/// The tensors (32 x 32, lbs_residual), made once per test binary.
fn tensors() -> &'static Path {
    static DIR: OnceLock<PathBuf> = OnceLock::new();
    DIR.get_or_init(|| {
        let dir = common::process_folder("train-test");
        let tensors = dir.join("tensors");
        tiny_tensors(&common::tiny_dataset(), &tensors, &[]);
        std::fs::write(dir.join("model.toml"), CONFIG).unwrap();
        tensors
    })
}

fn config() -> String {
    tensors()
        .parent()
        .unwrap()
        .join("model.toml")
        .display()
        .to_string()
}

fn train_args<'a>(run: &'a str, config: &'a str, extra: &[&'a str]) -> Vec<&'a str> {
    let data = tensors().to_str().unwrap();
    let mut args = vec![
        "train",
        "--data",
        data,
        "--out",
        run,
        "--config",
        config,
        "--threads",
        "1",
        "--quiet",
    ];
    args.extend_from_slice(extra);
    args
}

fn log(run: &Path) -> Vec<Value> {
    common::jsonl(&run.join("log.jsonl"))
}

/// The values a resumed run must reproduce exactly (wall times and speeds differ).
fn curve(log: &[Value]) -> Vec<[Value; 5]> {
    log.iter()
        .map(|l| ["step", "loss", "lr", "grad_norm", "val_loss"].map(|k| l[k].clone()))
        .collect()
}

#[test]
fn train_writes_every_output_and_numpy_reproduces_the_model() {
    let dir = tempfile::tempdir().unwrap();
    let run = dir.path().join("run");
    let cfg = config();
    ok(&train_args(run.to_str().unwrap(), &cfg, &[]));
    every_output_is_written(&run);
    the_weights_name_what_made_them(&run);
    the_weights_reproduce_the_reference_output(&run);
    numpy_reproduces_the_model(&run);
}

/// The run folder's files, the log's lines, the summary and the loss picture.
fn every_output_is_written(run: &Path) {
    for file in [
        "config.toml",
        "log.jsonl",
        "loss.png",
        "model.safetensors",
        "reference.safetensors",
        "summary.json",
        "checkpoint.json",
    ] {
        assert!(run.join(file).is_file(), "{file} missing");
    }
    let lines = log(run);
    assert_eq!(lines.len(), 12, "a line every 5 of 60 steps");
    for l in &lines {
        for key in ["step", "loss", "lr", "grad_norm", "samples_per_s", "wall_s"] {
            assert!(l[key].is_number(), "{key} in {l}");
        }
    }
    assert!(lines.iter().filter(|l| l["val_loss"].is_number()).count() == 6);
    let first = lines[0]["loss"].as_f64().unwrap();
    let last = lines.last().unwrap()["loss"].as_f64().unwrap();
    assert!(last < first, "the loss falls: {first} -> {last}");
    let summary = json(&run.join("summary.json"));
    for key in [
        "steps",
        "parameters",
        "final_loss",
        "best_val_loss",
        "wall_s",
        "samples_per_s",
        "config",
    ] {
        assert!(!summary[key].is_null(), "summary.{key}");
    }
    assert_eq!(summary["steps"], 60);
    assert_eq!(summary["config"]["model"]["resolution"], 32);
    assert_eq!(summary["config"]["model"]["target"], "lbs_residual");
    let png = image::open(run.join("loss.png")).unwrap();
    assert_eq!((png.width(), png.height()), (720, 420));
}

/// The weights name what made them: the run's config, the tensors' manifest, the commit.
fn the_weights_name_what_made_them(run: &Path) {
    let provenance = surrogate::run::Provenance::read(&run.join("model.safetensors"))
        .unwrap()
        .expect("model.safetensors carries its provenance");
    let sha = |path: &Path| files::sha256_file(path).unwrap().0;
    assert_eq!(provenance.config_sha256, sha(&run.join("config.toml")));
    assert_eq!(
        provenance.dataset_manifest_sha256,
        sha(&tensors().join("manifest.json"))
    );
    assert_eq!(provenance.commit, surrogate::run::COMMIT);
    assert!(
        provenance.commit == "unknown"
            || (provenance.commit.len() == 40
                && provenance.commit.bytes().all(|b| b.is_ascii_hexdigit())),
        "{}",
        provenance.commit
    );
}

/// The weights load back into the model they came from and reproduce the reference output;
/// weights for another configuration are refused, naming the file.
fn the_weights_reproduce_the_reference_output(run: &Path) {
    let device = surrogate::burn::prelude::Device::flex();
    let (loaded, model) = surrogate::run::load_run(run, &device).unwrap();
    assert_eq!(loaded.model.width, 16);
    let reference = std::fs::read(run.join("reference.safetensors")).unwrap();
    let reference = safetensors::SafeTensors::deserialize(&reference).unwrap();
    let tensor = |name: &str, dims: usize| {
        let t = reference.tensor(name).unwrap();
        let values: Vec<f32> = t
            .data()
            .chunks(4)
            .map(|b| f32::from_le_bytes(b.try_into().unwrap()))
            .collect();
        (values, t.shape().to_vec(), dims)
    };
    use surrogate::burn::prelude::{Tensor, TensorData};
    let t4 = |name: &str| {
        let (v, shape, _) = tensor(name, 4);
        Tensor::<4>::from_data(TensorData::new(v, shape), &device)
    };
    let (time, _, _) = tensor("timestep", 1);
    let (conditions, cshape, _) = tensor("conditions", 2);
    let out = model.forward(
        t4("noisy"),
        t4("position"),
        t4("mask"),
        Tensor::<1>::from_data(TensorData::new(time.clone(), [time.len()]), &device),
        Tensor::<2>::from_data(TensorData::new(conditions, cshape), &device),
    );
    let out: Vec<f32> = out.try_into_vec_as().unwrap();
    let (expected, _, _) = tensor("output", 4);
    assert_eq!(
        out, expected,
        "the loaded weights give the reference output"
    );
    let config_text = std::fs::read_to_string(run.join("config.toml")).unwrap();
    std::fs::write(
        run.join("config.toml"),
        config_text.replace("condition_tokens = 2", "condition_tokens = 3"),
    )
    .unwrap();
    let err = surrogate::run::load_run(run, &device)
        .expect_err("refused")
        .to_string();
    assert!(
        err.contains("model.safetensors") && err.contains("does not fit"),
        "{err}"
    );
    std::fs::write(run.join("config.toml"), &config_text).unwrap();
}

/// The NumPy reference (tools/dit_reference.py) computes the same output from the weights,
/// and disagrees when they are read with the wrong number of heads.
fn numpy_reproduces_the_model(run: &Path) {
    if python_has(
        "train::train_writes_every_output_and_numpy_reproduces_the_model",
        "numpy, safetensors, tomllib",
    ) {
        let tool = Path::new(env!("CARGO_MANIFEST_DIR")).join("tools/dit_reference.py");
        let check = |run: &Path| {
            std::process::Command::new("python3")
                .arg(&tool)
                .arg("--check")
                .arg(run)
                .output()
                .unwrap()
        };
        let out = check(run);
        assert!(
            out.status.success(),
            "{}{}",
            String::from_utf8_lossy(&out.stdout),
            String::from_utf8_lossy(&out.stderr)
        );
        // The check can fail: the same weights read as one head instead of two disagree.
        let text = std::fs::read_to_string(run.join("config.toml")).unwrap();
        std::fs::write(
            run.join("config.toml"),
            text.replace("heads = 2", "heads = 1"),
        )
        .unwrap();
        let out = check(run);
        assert_eq!(
            out.status.code(),
            Some(1),
            "{}",
            String::from_utf8_lossy(&out.stdout)
        );
    }
}

#[test]
fn a_killed_run_resumes_to_the_uninterrupted_curve() {
    let dir = tempfile::tempdir().unwrap();
    let cfg = config();
    let whole = dir.path().join("whole");
    ok(&train_args(whole.to_str().unwrap(), &cfg, &[]));

    let cut = dir.path().join("cut");
    let mut child = binary()
        .args(train_args(cut.to_str().unwrap(), &cfg, &[]))
        .spawn()
        .unwrap();
    let started = Instant::now();
    while !cut.join("checkpoint.json").exists() {
        assert!(
            started.elapsed() < Duration::from_secs(120),
            "no checkpoint after 2 minutes"
        );
        std::thread::sleep(Duration::from_millis(2));
    }
    child.kill().unwrap(); // SIGKILL: no clean-up of any kind
    child.wait().unwrap();
    assert!(
        !cut.join("summary.json").exists(),
        "the run finished before it was killed"
    );
    ok(&train_args(cut.to_str().unwrap(), &cfg, &["--resume"]));
    assert_eq!(curve(&log(&cut)), curve(&log(&whole)));
    for file in ["model.safetensors", "best.safetensors"] {
        assert!(
            same_weights(&cut.join(file), &whole.join(file)),
            "{file} differs"
        );
    }
}

/// Whether two safetensors files hold the same tensors, value for value (their metadata
/// aside).
fn same_weights(a: &Path, b: &Path) -> bool {
    let (a, b) = (std::fs::read(a).unwrap(), std::fs::read(b).unwrap());
    let (a, b) = (
        safetensors::SafeTensors::deserialize(&a).unwrap(),
        safetensors::SafeTensors::deserialize(&b).unwrap(),
    );
    a.len() == b.len()
        && a.tensors()
            .iter()
            .all(|(name, t)| b.tensor(name).is_ok_and(|u| u.data() == t.data()))
}

/// With `training.keep_best` the shipped weights are the EMA of the lowest validation loss
/// (`best.safetensors`), the summary names its step and the reference output is theirs; the
/// same run without it ships the last step's EMA and keeps the same `best.safetensors`.
#[test]
fn keep_best_ships_the_weights_of_the_lowest_validation_loss() {
    let dir = tempfile::tempdir().unwrap();
    // A learning rate high enough that the validation loss is not lowest at the last step.
    let recipe = CONFIG.replace("lr = 1e-3", "lr = 3e-2");
    let train = |name: &str, keep_best: bool| {
        let config = dir.path().join(format!("{name}.toml"));
        std::fs::write(&config, format!("{recipe}keep_best = {keep_best}\n")).unwrap();
        let run = dir.path().join(name);
        ok(&train_args(
            run.to_str().unwrap(),
            config.to_str().unwrap(),
            &[],
        ));
        (run.clone(), json(&run.join("summary.json")))
    };
    let (best, summary) = train("best", true);
    let lines = log(&best);
    let (step, lowest) = lines
        .iter()
        .filter_map(|l| Some((l["step"].as_u64()?, l["val_loss"].as_f64()?)))
        .min_by(|a, b| a.1.total_cmp(&b.1))
        .unwrap();
    assert!(
        step < 60,
        "the lowest validation loss is at the end: {lines:?}"
    );
    assert_eq!(summary["best_val_step"], step);
    assert_eq!(summary["model_step"], step);
    assert_eq!(summary["best_val_loss"].as_f64(), Some(lowest));
    assert!(same_weights(
        &best.join("model.safetensors"),
        &best.join("best.safetensors")
    ));
    the_weights_name_what_made_them(&best);
    the_weights_reproduce_the_reference_output(&best);

    let (last, summary) = train("last", false);
    assert_eq!(summary["model_step"], 60);
    assert_eq!(summary["best_val_step"], step);
    assert!(same_weights(
        &last.join("best.safetensors"),
        &best.join("best.safetensors")
    ));
    assert!(!same_weights(
        &last.join("model.safetensors"),
        &best.join("model.safetensors")
    ));
}

#[test]
fn a_finished_run_resumed_with_more_steps_continues_its_log() {
    let dir = tempfile::tempdir().unwrap();
    let cfg = config();
    let run = dir.path().join("run");
    let run_s = run.to_str().unwrap();
    ok(&train_args(run_s, &cfg, &["--steps", "20"]));
    let first = log(&run);
    let said = ok(&train_args(run_s, &cfg, &["--steps", "40", "--resume"]));
    assert!(
        said.contains("extending the run from 20 to 40 steps"),
        "{said}"
    );
    let extended = log(&run);
    // The first 20 steps are kept as they were; the run goes on to step 40.
    assert_eq!(curve(&extended[..first.len()]), curve(&first));
    assert_eq!(extended.last().unwrap()["step"], 40);
    // From step 20 on, the learning rate is the 40-step schedule's (a 40-step run's).
    // Without --quiet and without a terminal (the bar hidden), each log line is printed.
    assert!(!said.contains("step 30/40"), "{said}");
    let straight = dir.path().join("straight");
    let loud: Vec<&str> = train_args(straight.to_str().unwrap(), &cfg, &["--steps", "40"])
        .into_iter()
        .filter(|a| *a != "--quiet")
        .collect();
    let said = ok(&loud);
    assert!(said.contains("step 30/40: loss "), "{said}");
    let lr = |log: &[Value]| -> Vec<(Value, Value)> {
        log.iter()
            .filter(|l| l["step"].as_u64().unwrap() > 20)
            .map(|l| (l["step"].clone(), l["lr"].clone()))
            .collect()
    };
    assert!(!lr(&extended).is_empty());
    assert_eq!(lr(&extended), lr(&log(&straight)));
    let saved = std::fs::read_to_string(run.join("config.toml")).unwrap();
    assert!(saved.contains("steps = 40"), "{saved}");
}

#[test]
fn bad_configurations_and_damaged_checkpoints_are_named() {
    let dir = tempfile::tempdir().unwrap();
    let cfg = config();
    let bad = dir.path().join("bad.toml");
    std::fs::write(&bad, "[model]\nwidht = 16\n").unwrap();
    let run = dir.path().join("run");
    let run_s = run.to_str().unwrap();
    let err = fails(&train_args(run_s, bad.to_str().unwrap(), &[]));
    assert!(
        err.contains("bad.toml") && err.contains("model.widht"),
        "{err}"
    );
    std::fs::write(&bad, "[training]\nlr = 0.0\n").unwrap();
    let err = fails(&train_args(run_s, bad.to_str().unwrap(), &[]));
    assert!(err.contains("training.lr = 0"), "{err}");
    assert!(!run.exists(), "nothing written for a bad configuration");

    ok(&train_args(run_s, &cfg, &["--steps", "20"]));
    let err = fails(&train_args(run_s, &cfg, &["--steps", "20"]));
    assert!(err.contains("already holds a training run"), "{err}");
    let err = fails(&train_args(run_s, &cfg, &["--steps", "10", "--resume"]));
    assert!(err.contains("training.steps = 10 here, 20 there"), "{err}");

    let pointer = json(&run.join("checkpoint.json"));
    let checkpoint = run.join(pointer["dir"].as_str().unwrap());
    let args = train_args(run_s, &cfg, &["--steps", "20", "--resume"]);
    checkpoints_of_other_models_and_damaged_files_are_refused(&checkpoint, &args);
    a_resume_that_cannot_continue_changes_nothing(dir.path(), &run, &checkpoint, &cfg);
}

/// A checkpoint made for another model is refused naming the file and the key; a damaged
/// model file is named, and so is random damage (seeded: 1 to 8 bytes anywhere in each file
/// of the checkpoint): the checksums written with the checkpoint catch what burnpack would
/// load. `resume` are the arguments that resume the run.
fn checkpoints_of_other_models_and_damaged_files_are_refused(checkpoint: &Path, resume: &[&str]) {
    let saved = checkpoint.join("config.toml");
    let text = std::fs::read_to_string(&saved).unwrap();
    std::fs::write(&saved, text.replace("width = 16", "width = 32")).unwrap();
    let err = fails(resume);
    assert!(
        err.contains("config.toml") && err.contains("model.width = 16 here, 32 there"),
        "{err}"
    );
    std::fs::write(&saved, text).unwrap();

    let sums = checkpoint.join("checksums.json");
    let kept = std::fs::read(&sums).unwrap();
    std::fs::remove_file(&sums).unwrap();
    let err = fails(resume);
    assert!(
        err.contains("checksums.json") && err.contains("missing"),
        "{err}"
    );
    std::fs::write(&sums, kept).unwrap();

    let model = checkpoint.join("model.bpk");
    let bytes = std::fs::read(&model).unwrap();
    std::fs::write(&model, &bytes[..bytes.len() / 2]).unwrap();
    let err = fails(resume);
    assert!(
        err.contains("model.bpk") && err.contains("damaged"),
        "{err}"
    );

    let mut state: u64 = 27;
    let mut random = |n: usize| {
        state = state
            .wrapping_mul(6364136223846793005)
            .wrapping_add(1442695040888963407);
        ((state >> 33) as usize) % n
    };
    for file in ["model.bpk", "optim.bpk", "ema.bpk"] {
        let path = checkpoint.join(file);
        let original = if file == "model.bpk" {
            bytes.clone()
        } else {
            std::fs::read(&path).unwrap()
        };
        for case in 0..6 {
            let mut damaged = original.clone();
            for _ in 0..=random(8) {
                let at = random(damaged.len());
                damaged[at] ^= 1 + random(255) as u8;
            }
            std::fs::write(&path, &damaged).unwrap();
            let out = run_with(resume, &[]);
            let stderr = String::from_utf8_lossy(&out.stderr);
            assert_eq!(out.status.code(), Some(1), "{file} case {case}: {stderr}");
            assert!(
                stderr.contains(file) && stderr.contains("damaged"),
                "{file} case {case}: {stderr}"
            );
        }
        std::fs::write(&path, &original).unwrap();
    }
}

/// A resume that cannot continue changes nothing: a checkpoint of another configuration
/// leaves the run as it was; a finished model without checkpoints (as the shipped ones are),
/// or checkpoints without checkpoint.json, is never retrained over.
fn a_resume_that_cannot_continue_changes_nothing(
    dir: &Path,
    run: &Path,
    checkpoint: &Path,
    cfg: &str,
) {
    let run_s = run.to_str().unwrap();
    let saved = checkpoint.join("config.toml");
    let files_of = |dir: &Path| -> Vec<(String, Vec<u8>)> {
        let mut all: Vec<(String, Vec<u8>)> = std::fs::read_dir(dir)
            .unwrap()
            .flatten()
            .filter(|e| e.path().is_file())
            .map(|e| {
                let name = e.file_name().to_string_lossy().into_owned();
                (name, std::fs::read(e.path()).unwrap())
            })
            .collect();
        all.sort();
        all
    };
    let text = std::fs::read_to_string(&saved).unwrap();
    std::fs::write(&saved, text.replace("lr = ", "lr = 0.5 #")).unwrap();
    let before = files_of(run);
    fails(&train_args(run_s, cfg, &["--steps", "20", "--resume"]));
    assert!(
        files_of(run) == before,
        "a refused resume rewrote the run folder"
    );
    std::fs::write(&saved, text).unwrap();
    let finished = dir.join("finished");
    std::fs::create_dir_all(&finished).unwrap();
    for file in ["config.toml", "tensors.json", "model.safetensors"] {
        std::fs::copy(run.join(file), finished.join(file)).unwrap();
    }
    let before = files_of(&finished);
    let finished_s = finished.to_str().unwrap();
    let err = fails(&train_args(finished_s, cfg, &["--steps", "20", "--resume"]));
    assert!(
        err.contains("a finished model without checkpoints"),
        "{err}"
    );
    assert!(
        files_of(&finished) == before,
        "the finished model was touched"
    );
    std::fs::remove_file(run.join("checkpoint.json")).unwrap();
    let err = fails(&train_args(run_s, cfg, &["--steps", "20", "--resume"]));
    assert!(
        err.contains("a finished model without checkpoints"),
        "{err}"
    );
    std::fs::remove_file(run.join("model.safetensors")).unwrap();
    let err = fails(&train_args(run_s, cfg, &["--steps", "20", "--resume"]));
    assert!(
        err.contains("checkpoint folders without the checkpoint.json"),
        "{err}"
    );
}
