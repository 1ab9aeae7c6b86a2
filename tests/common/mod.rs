//! Running the `dit-garment` binary as a user does, for the end-to-end tests.

#![allow(dead_code)] // each test file uses its own subset

use std::path::{Path, PathBuf};
use std::process::{Command, Output};

use serde_json::Value;

/// The binary, with library templates cached in a folder of the tests' own and no scheduler
/// variables inherited (they would pick a shard).
pub fn binary() -> Command {
    let mut c = Command::new(env!("CARGO_BIN_EXE_dit-garment"));
    c.env(
        "DIT_GARMENT_CACHE",
        std::env::temp_dir().join("dit-garment-test-cache"),
    );
    for v in [
        "SLURM_ARRAY_TASK_ID",
        "SLURM_ARRAY_TASK_COUNT",
        "SLURM_ARRAY_TASK_MIN",
        "JOB_COMPLETION_INDEX",
    ] {
        c.env_remove(v);
    }
    c
}

/// Runs the binary with extra environment variables.
pub fn run_with(args: &[&str], env: &[(&str, &str)]) -> Output {
    let mut c = binary();
    c.args(args);
    for (k, v) in env {
        c.env(k, v);
    }
    c.output().expect("the binary runs")
}

/// Runs the binary, asserts success and returns its standard output.
pub fn ok(args: &[&str]) -> String {
    let out = run_with(args, &[]);
    assert!(
        out.status.success(),
        "{args:?} failed: {}{}",
        String::from_utf8_lossy(&out.stdout),
        String::from_utf8_lossy(&out.stderr)
    );
    String::from_utf8_lossy(&out.stdout).to_string()
}

/// Runs the binary, asserts failure and returns its standard error.
pub fn fails(args: &[&str]) -> String {
    let out = run_with(args, &[]);
    let stderr = String::from_utf8_lossy(&out.stderr).to_string();
    // A refusal exits with 1; 101 would be a panic, none a signal.
    assert_eq!(
        out.status.code(),
        Some(1),
        "{args:?} should fail with 1: {stderr}"
    );
    // The error is one line, the last one (progress may come before it).
    let errors: Vec<&str> = stderr.lines().filter(|l| l.starts_with("error:")).collect();
    assert!(
        errors.len() == 1 && stderr.trim_end().ends_with(errors[0].trim_end()),
        "{args:?} should end with one error line: {stderr}"
    );
    stderr
}

/// A JSON file.
pub fn json(path: &Path) -> Value {
    serde_json::from_str(&std::fs::read_to_string(path).unwrap()).unwrap()
}

/// A JSON Lines file, one value per line.
pub fn jsonl(path: &Path) -> Vec<Value> {
    std::fs::read_to_string(path)
        .unwrap()
        .lines()
        .map(|l| serde_json::from_str(l).unwrap())
        .collect()
}

/// Whether `python3` can import `modules` (comma-separated) for the Python part of `test`.
/// Where it cannot, the caller skips that part, recorded by `testkit::available`, unless
/// `DIT_GARMENT_REQUIRE_PYTHON` is set (`.ci/run` sets it after installing the packages),
/// which makes a missing package a failure instead.
pub fn python_has(test: &str, modules: &str) -> bool {
    let found = std::process::Command::new("python3")
        .args(["-c", &format!("import {modules}")])
        .status()
        .is_ok_and(|s| s.success());
    testkit::available(
        test,
        "PYTHON",
        found,
        &format!("python3 cannot import {modules}"),
    )
}

/// Runs one of the independent format readers (`tests/readers/*.py`, public packages only) on `arg`, asserts success and parses the JSON it prints.
pub fn python_tool(script: &str, arg: &Path) -> Value {
    let script = Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("tests/readers")
        .join(script);
    let out = Command::new("python3")
        .arg(script)
        .arg(arg)
        .output()
        .expect("python3 runs");
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    serde_json::from_slice(&out.stdout).expect("the tool prints JSON")
}

/// The tiny dataset spec of the end-to-end tests, named `name` and seeded by `seed`: one
/// skirt sequence on `walk` (train) and one on `arm_swing` (`test_motion`, a motion the train
/// split never sees), 12 frames each, at a fast solver setting. One spec for every test file
/// that needs a dataset to train or score on.
pub fn tiny_spec(name: &str, seed: u64) -> String {
    format!(
        r#"name = "{name}"
seed = {seed}
[sequence]
frames = 12
blend_frames = 3
settle_frames = 1
shapes_per_motion = 1
draws_per_shape = 1
[solver]
substeps = 1
max_iterations = 4
[[garments]]
name = "skirt"
split = "train"
[[motions]]
source = "walk"
split = "train"
[[motions]]
source = "arm_swing"
split = "test"
[splits]
test_motion = 1
"#
    )
}

/// The tiny dataset ([`tiny_spec`] named `tiny`, seed 5) every end-to-end test that trains
/// or scores on one shares, synthesized once per build of the binary: in a folder of the temp
/// dir named by the binary's modification time and size (a rebuilt engine makes it anew),
/// under a file lock so test binaries run side by side do not synthesize it twice. Tests
/// must not change it: one that damages a dataset copies it first.
pub fn tiny_dataset() -> PathBuf {
    static DATA: std::sync::OnceLock<PathBuf> = std::sync::OnceLock::new();
    DATA.get_or_init(|| {
        let exe = std::fs::metadata(env!("CARGO_BIN_EXE_dit-garment")).unwrap();
        let built = exe
            .modified()
            .unwrap()
            .duration_since(std::time::UNIX_EPOCH)
            .unwrap()
            .as_nanos();
        let dir = std::env::temp_dir().join(format!("dit-garment-tiny-{built:x}-{}", exe.len()));
        std::fs::create_dir_all(&dir).unwrap();
        let lock = std::fs::File::create(dir.join("lock")).unwrap();
        lock.lock().unwrap();
        let data = dir.join("data");
        if !data.join("manifest.jsonl").is_file() {
            // Resumes a synthesis a killed test run left half done.
            synth_spec(&dir, "data", &tiny_spec("tiny", 5));
        }
        data
    })
    .clone()
}

/// Synthesizes `spec` into `dir/<name>` (the spec written beside it as `<name>.toml`).
pub fn synth_spec(dir: &Path, name: &str, spec: &str) -> PathBuf {
    let path = dir.join(format!("{name}.toml"));
    std::fs::write(&path, spec).unwrap();
    let data = dir.join(name);
    ok(&[
        "synth",
        "--spec",
        path.to_str().unwrap(),
        "--out",
        data.to_str().unwrap(),
        "--quiet",
    ]);
    data
}

/// `dataset tensors` of `data` into `out` at 32 x 32 with `lbs_residual` targets, with
/// `extra` flags.
pub fn tiny_tensors(data: &Path, out: &Path, extra: &[&str]) {
    let mut args = vec![
        "dataset",
        "tensors",
        data.to_str().unwrap(),
        "--out",
        out.to_str().unwrap(),
        "--resolution",
        "32",
        "--target",
        "lbs_residual",
        "--quiet",
    ];
    args.extend_from_slice(extra);
    ok(&args);
}

/// A tiny trained run and what it was made from.
pub struct TinyRun {
    /// The folder holding all of it.
    pub dir: PathBuf,
    /// The synthesized dataset.
    pub data: PathBuf,
    /// Its tensors.
    pub tensors: PathBuf,
    /// The trained run.
    pub run: PathBuf,
    /// The run's configuration file.
    pub config: PathBuf,
    /// The simulated `test_motion` sequence.
    pub truth: PathBuf,
}

/// A fresh folder `<temp>/dit-garment-<name>-<pid>` for one test binary's shared fixture.
/// Statics are never dropped, so such folders outlive their process: the ones of processes
/// that have ended (no `/proc/<pid>`) are removed first.
pub fn process_folder(name: &str) -> PathBuf {
    let temp = std::env::temp_dir();
    if Path::new("/proc/self").exists()
        && let Ok(entries) = std::fs::read_dir(&temp)
    {
        let prefix = format!("dit-garment-{name}-");
        for entry in entries.flatten() {
            let file_name = entry.file_name();
            let pid = file_name.to_str().and_then(|f| f.strip_prefix(&prefix));
            if let Some(pid) = pid.filter(|p| p.bytes().all(|b| b.is_ascii_digit()))
                && !Path::new("/proc").join(pid).exists()
            {
                let _ = std::fs::remove_dir_all(entry.path());
            }
        }
    }
    let dir = temp.join(format!("dit-garment-{name}-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).unwrap();
    dir
}

/// The fixture of the tests that predict: the shared tiny dataset ([`tiny_dataset`]), its
/// tensors (with `tensor_flags`) and `config` trained on them on one thread, in a fresh folder
/// `<temp>/dit-garment-<name>-<pid>`.
pub fn tiny_run(name: &str, tensor_flags: &[&str], config: &str) -> TinyRun {
    let dir = process_folder(name);
    let (tensors, run, config_path) = (dir.join("tensors"), dir.join("run"), dir.join("m.toml"));
    std::fs::write(&config_path, config).unwrap();
    let data = tiny_dataset();
    tiny_tensors(&data, &tensors, tensor_flags);
    let path = |p: &Path| p.to_str().unwrap().to_string();
    let (t, r, c) = (path(&tensors), path(&run), path(&config_path));
    ok(&[
        "train",
        "--data",
        &t,
        "--out",
        &r,
        "--config",
        &c,
        "--threads",
        "1",
        "--quiet",
    ]);
    let truth = std::fs::read_dir(data.join("sequences"))
        .unwrap()
        .map(|e| e.unwrap().path())
        .find(|p| {
            p.file_name()
                .unwrap()
                .to_string_lossy()
                .starts_with("test_motion")
        })
        .expect("the test sequence");
    TinyRun {
        dir,
        data,
        tensors,
        run,
        config: config_path,
        truth,
    }
}

/// The tiny network of the tests that predict (width 16, one block, patch 4), trained for 10
/// steps, with `model` and `training` keys added to its tables.
pub fn tiny_config(model: &str, training: &str) -> String {
    format!(
        "[model]\npatch = 4\nwidth = 16\ndepth = 1\nheads = 2\nmlp_ratio = 2.0\n\
         condition_tokens = 2\n{model}[training]\nsteps = 10\nbatch = 2\nlr = 1e-3\n\
         warmup_steps = 2\nlog_every = 5\nval_every = 10\ncheckpoint_every = 10\nval_frames = 4\n\
         {training}"
    )
}
