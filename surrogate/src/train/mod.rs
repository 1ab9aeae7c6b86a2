//! Training with rectified flow: z_s = (1 - s) z0 + s eps, the network predicts z0 or the
//! velocity eps - z0 (`model.prediction`; the standard interpolation, the paper's
//! DDPM-schedule formula is not rectified flow, docs/SURROGATE.md), AdamW with warm-up and cosine decay, global-norm clipping, an EMA
//! of the weights, a fixed validation set, checkpoints every K steps and exact resume.
//!
//! A run folder holds `config.toml`, `tensors.json` (the manifest of the tensors trained on:
//! what sampling needs of the data), `log.jsonl`, `loss.png`, `checkpoint-<step>/`,
//! `model.safetensors` (EMA), `best.safetensors` (the EMA at the lowest validation loss),
//! `reference.safetensors` and `summary.json`, each written through a temporary name.

mod batch;
pub(crate) mod checkpoint;
mod optim;
mod reference;
mod rollout;

use std::path::{Path, PathBuf};
use std::time::Instant;

use burn::optim::GradientsParams;
use burn::prelude::*;
use serde::{Deserialize, Serialize};

pub use batch::{Batch, Recipe, validation_batches};
pub use checkpoint::{Loaded, RunState, load as load_checkpoint};
use files::write_atomic;
pub use optim::{average_decay, clip_global_norm, ema_decay, update_ema};
pub use reference::save_reference;

use crate::data::{Frames, TrainingTensors};
use crate::error::{Error, Result, file_error};
use crate::model::Dit;
use crate::noise::generator;
use crate::run::{
    COMMIT, Provenance, RunConfig, TENSORS_MANIFEST, TrainConfig, load_weights, save_weights,
};

/// The EMA weights of the lowest validation loss so far, in the run folder.
pub const BEST_WEIGHTS: &str = "best.safetensors";

/// One line of `log.jsonl`.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct LogLine {
    /// Steps done.
    pub step: usize,
    /// Mean training loss over the steps since the previous line.
    pub loss: f64,
    /// Learning rate of the last step.
    pub lr: f64,
    /// Mean global gradient norm (before clipping) over those steps.
    pub grad_norm: f64,
    /// Frames per second of wall time over those steps.
    pub samples_per_s: f64,
    /// Wall time of the run so far (all sessions), s.
    pub wall_s: f64,
    /// Validation loss of the EMA weights, where evaluated.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub val_loss: Option<f64>,
}

/// `summary.json`.
#[derive(Debug, Clone, Serialize, Deserialize)]
pub struct Summary {
    /// Steps done.
    pub steps: usize,
    /// Trainable parameters.
    pub parameters: usize,
    /// The last logged training loss.
    pub final_loss: f64,
    /// Lowest validation loss (EMA weights), if any was evaluated.
    pub best_val_loss: Option<f64>,
    /// The step of that loss (`best.safetensors` holds its weights).
    #[serde(default)]
    pub best_val_step: Option<usize>,
    /// The step whose EMA weights `model.safetensors` holds: the last one, or with
    /// `training.keep_best` the best one.
    #[serde(default)]
    pub model_step: usize,
    /// Wall time of all sessions, s.
    pub wall_s: f64,
    /// Frames per second of wall time over the run.
    pub samples_per_s: f64,
    /// The run's configuration.
    pub config: RunConfig,
}

/// What to train.
#[derive(Debug, Clone)]
pub struct TrainOptions {
    /// The tensors folder (`dataset tensors` output).
    pub data: PathBuf,
    /// The run folder.
    pub out: PathBuf,
    /// Model and training; `model.resolution`, `condition_dim` and `target` are taken from
    /// the tensors (see [`RunConfig::fit_to`]).
    pub config: RunConfig,
    /// Stop (at the next log line) after this many minutes of this session.
    pub minutes: Option<f64>,
    /// Continue the run in `out` from its last checkpoint.
    pub resume: bool,
    /// The device to train on (its autodiff twin takes the gradients).
    pub device: Device,
}

/// What training reports as it goes.
#[derive(Debug, Clone)]
pub enum Event {
    /// Training starts (or resumes) at `step` of `steps`.
    Started {
        /// Steps already done.
        step: usize,
        /// Steps of the run.
        steps: usize,
        /// The run's steps before this resume extended them: the learning rate from `step` on
        /// follows the `steps`-step schedule.
        extended_from: Option<usize>,
        /// Trainable parameters.
        parameters: usize,
        /// Training frames.
        train_frames: usize,
        /// Validation frames.
        val_frames: usize,
        /// The split they come from (none when no held-out split has frames).
        val_split: Option<String>,
    },
    /// A step finished with this loss.
    Step {
        /// Steps done.
        step: usize,
        /// Its loss.
        loss: f64,
    },
    /// A log line was written.
    Log(LogLine),
}

/// The weighted validation loss of `model` over `batches`, run on `device`.
fn validation_loss(model: &Dit, batches: &[Batch], device: &Device) -> Option<f64> {
    let (mut sum, mut weight) = (0.0, 0.0);
    for b in batches {
        let (noisy, position, mask, time, conditions) = b.inputs(device);
        let loss = b.loss(model.forward(noisy, position, mask, time, conditions));
        let w: f64 = b.weight.iter().map(|&w| f64::from(w)).sum();
        sum += f64::from(loss.into_scalar::<f32>()) * w;
        weight += w;
    }
    (weight > 0.0).then(|| sum / weight)
}

fn write_log(run: &Path, log: &[LogLine]) -> Result<()> {
    let text: String = log
        .iter()
        .map(|l| serde_json::to_string(l).expect("a log line serializes") + "\n")
        .collect();
    Ok(write_atomic(&run.join("log.jsonl"), text.as_bytes())?)
}

fn read_log(run: &Path, up_to: usize) -> Result<Vec<LogLine>> {
    let path = run.join("log.jsonl");
    if !path.exists() {
        return Ok(Vec::new());
    }
    // An unreadable log is an error: resuming without it would erase the run's history.
    let log: Vec<LogLine> = files::read_json_lines(&path, "training log")?;
    Ok(log.into_iter().filter(|l| l.step <= up_to).collect())
}

/// Draws `loss.png`: training and validation loss against step.
fn plot(run: &Path, log: &[LogLine]) -> Result<()> {
    let train: Vec<(f64, f64)> = log.iter().map(|l| (l.step as f64, l.loss)).collect();
    let val: Vec<(f64, f64)> = log
        .iter()
        .filter_map(|l| l.val_loss.map(|v| (l.step as f64, v)))
        .collect();
    let series = [
        render::Series {
            name: "train",
            points: &train,
            colour: [31, 119, 180],
        },
        render::Series {
            name: "validation (EMA)",
            points: &val,
            colour: [214, 39, 40],
        },
    ];
    let path = run.join("loss.png");
    let image = render::log_line_chart("rectified-flow loss", "step", &series, 720, 420)
        .map_err(|e| file_error(&path, e))?;
    let mut bytes = Vec::new();
    render::write_png(&mut bytes, &image).map_err(|e| file_error(&path, e))?;
    Ok(write_atomic(&path, &bytes)?)
}

/// Trains (or resumes) a run; `progress` hears every step and log line. Stages: the checks
/// (nothing is written before they pass), the run's files, the data, the network (fresh or
/// from the last checkpoint), the steps with their log lines and checkpoints, the outputs.
pub fn train(options: &TrainOptions, progress: &mut dyn FnMut(Event)) -> Result<Summary> {
    let tensors = TrainingTensors::open(&options.data)?;
    let mut config = options.config.clone();
    config.fit_to(&tensors);
    config.validate()?;
    check_tensors(&config, &tensors, &options.data)?;
    let extended_from = check_resume(options, &config)?;
    write_run_files(&options.out, &config, &tensors)?;
    let data = TrainingData::new(tensors, &options.data, &config)?;
    let device = options.device.clone().autodiff();
    device.seed(config.training.seed);
    let loaded = if options.resume {
        checkpoint::load(&options.out, &config, &device)?
    } else {
        None
    };
    let net = loaded.unwrap_or_else(|| fresh(&config, &device));
    let mut log = read_log(&options.out, net.state.step)?;
    progress(Event::Started {
        step: net.state.step,
        steps: config.training.steps,
        extended_from,
        parameters: net.model.parameters(),
        train_frames: data.train.len(),
        val_frames: data.val_batches.iter().map(|b| b.size).sum(),
        val_split: data.val_split.clone(),
    });
    let (net, saved_at) = run_steps(options, &config, &data, net, &mut log, &device, progress)?;
    finish(options, &config, &data, &net, &log, saved_at)
}

/// Refuses tensors that lack what the model takes: body channels, every frame for the
/// previous state.
fn check_tensors(config: &RunConfig, tensors: &TrainingTensors, data: &Path) -> Result<()> {
    let (wanted, stored) = (
        config.model.body_channels(),
        tensors.manifest.body_channels(),
    );
    let refuse = |message: String| {
        Err(Error::Config {
            path: "the training configuration".into(),
            message,
        })
    };
    if wanted > stored {
        return refuse(format!(
            "the model takes {wanted} body input channels (model.body_inputs, model.body_nearest), but the tensors in {} have {stored} (body inputs need the lbs_residual target, the nearest-body ones `dataset tensors --body-nearest`): remake them or turn the keys off",
            data.display()
        ));
    }
    if config.model.previous_state && tensors.manifest.every != 1 {
        return refuse(format!(
            "model.previous_state needs every frame of a sequence, but the tensors in {} keep every {}th (remake them without --every)",
            data.display(),
            tensors.manifest.every
        ));
    }
    Ok(())
}

/// Whether the run folder may be trained into: a new run into a folder without one, a resume
/// into a run it can continue (refused here, before a file is written, if it cannot).
/// Returns the run's steps before this resume extended them, if it does.
fn check_resume(options: &TrainOptions, config: &RunConfig) -> Result<Option<usize>> {
    let run = &options.out;
    let config_path = run.join("config.toml");
    if !options.resume {
        if config_path.exists() || run.join("checkpoint.json").exists() {
            return Err(file_error(
                run,
                "already holds a training run (pass --resume to continue it, or choose a new folder)",
            ));
        }
        return Ok(None);
    }
    let mut extended_from = None;
    if config_path.exists() {
        let saved = RunConfig::load_saved(&config_path)?;
        if config.training.steps > saved.training.steps {
            extended_from = Some(saved.training.steps);
        }
        if let Some(d) = config.resume_difference(&saved) {
            return Err(file_error(
                &config_path,
                format!(
                    "the run was started with another configuration ({d}); resume without changing it"
                ),
            ));
        }
    }
    checkpoint::resumable(run, config)?;
    Ok(extended_from)
}

/// `config.toml` and what sampling needs of the data (`tensors.json`: normalization,
/// condition layout, target, frames).
fn write_run_files(run: &Path, config: &RunConfig, tensors: &TrainingTensors) -> Result<()> {
    std::fs::create_dir_all(run).map_err(|e| file_error(run, e))?;
    write_atomic(&run.join("config.toml"), config.to_toml().as_bytes())?;
    let manifest = serde_json::to_vec_pretty(&tensors.manifest).map_err(|e| file_error(run, e))?;
    Ok(write_atomic(&run.join(TENSORS_MANIFEST), &manifest)?)
}

/// The frames a run trains and validates on, and how batches are made of them.
struct TrainingData {
    tensors: TrainingTensors,
    train: Frames,
    val: Frames,
    val_split: Option<String>,
    val_batches: Vec<Batch>,
    recipe: Recipe,
}

impl TrainingData {
    fn new(tensors: TrainingTensors, dir: &Path, config: &RunConfig) -> Result<Self> {
        let t = &config.training;
        let train = tensors.frames("train")?;
        if train.is_empty() {
            return Err(file_error(dir, "has no training frames"));
        }
        let val_split = held_out_split(&tensors, &t.val_split);
        let val = match &val_split {
            Some(split) => tensors.frames(split)?,
            None => Frames::default(),
        };
        let recipe = Recipe::new(&config.model, t);
        let val_batches = validation_batches(&tensors, &val, t, recipe);
        Ok(Self {
            tensors,
            train,
            val,
            val_split,
            val_batches,
            recipe,
        })
    }
}

/// A new network (output layers at zero where configured), its EMA, a fresh optimizer.
fn fresh(config: &RunConfig, device: &Device) -> Loaded {
    let mut model = Dit::new(&config.model, device);
    if config.training.zero_init {
        model = model.zero_output_layers();
    }
    Loaded {
        ema: model.valid(),
        model,
        optim: checkpoint::optimizer(&config.training),
        state: RunState {
            step: 0,
            wall_s: 0.0,
            best_val_loss: None,
            best_val_step: None,
        },
    }
}

/// The device generator's seed for the dropout masks of `step` (0-based) of a run seeded
/// `seed`: distinct per step, and apart from the seed that drew the initial weights.
fn dropout_seed(seed: u64, step: usize) -> u64 {
    seed.wrapping_mul(0x9E37_79B9_7F4A_7C15)
        .wrapping_add(step as u64 + 1)
        .rotate_left(17)
}

/// Sums over the steps since the last log line.
struct Interval {
    loss: f64,
    grad_norm: f64,
    steps: usize,
    started: Instant,
}

impl Interval {
    fn new() -> Self {
        Self {
            loss: 0.0,
            grad_norm: 0.0,
            steps: 0,
            started: Instant::now(),
        }
    }
}

/// The optimizer steps from the last one done to the run's end (or the session's time
/// limit), with a log line every `log_every` steps (the EMA's validation loss every
/// `val_every`) and a checkpoint every `checkpoint_every`. Returns the network and the step
/// of its last checkpoint.
fn run_steps(
    options: &TrainOptions,
    config: &RunConfig,
    data: &TrainingData,
    mut net: Loaded,
    log: &mut Vec<LogLine>,
    device: &Device,
    progress: &mut dyn FnMut(Event),
) -> Result<(Loaded, usize)> {
    let (t, run) = (&config.training, &options.out);
    let session = Instant::now();
    let wall_before = net.state.wall_s;
    let mut interval = Interval::new();
    let mut saved_at = net.state.step;
    while net.state.step < t.steps {
        let step = net.state.step;
        let batch = if t.rollout > 0 {
            let unrolled = net.model.valid();
            Batch::training_with(&data.tensors, &data.train, t, data.recipe, step, |frames| {
                rollout::own_previous(&unrolled, data, frames, t, step, &options.device)
            })
        } else {
            Batch::training(&data.tensors, &data.train, t, data.recipe, step)
        };
        let (noisy, position, mask, time, conditions) = batch.inputs(device);
        if t.dropout > 0.0 {
            // The masks of step k come from a generator seeded by (seed, k), so that a resumed
            // run draws the masks the uninterrupted one drew.
            device.seed(dropout_seed(t.seed, step));
        }
        let out = net
            .model
            .forward_dropping(noisy, position, mask, time, conditions, t.dropout);
        let loss = batch.loss(out);
        let loss_value = f64::from(loss.clone().into_scalar::<f32>());
        if !loss_value.is_finite() {
            return Err(Error::Diverged {
                step: step + 1,
                loss: loss_value,
                config: run.join("config.toml").display().to_string(),
            });
        }
        let mut grads = GradientsParams::from_grads(loss.backward(), &net.model);
        let grad_norm = clip_global_norm(&net.model, &mut grads, t.grad_clip_norm);
        let lr = t.lr_at(step);
        net.model = net.optim.step(lr, net.model, grads);
        net.ema = update_ema(net.ema, &net.model, average_decay(t, step));
        net.state.step += 1;
        net.state.wall_s = wall_before + session.elapsed().as_secs_f64();
        interval.loss += loss_value;
        interval.grad_norm += grad_norm;
        interval.steps += 1;
        let done = net.state.step;
        progress(Event::Step {
            step: done,
            loss: loss_value,
        });
        if !done.is_multiple_of(t.log_every) && done != t.steps {
            continue;
        }
        let line = log_line(
            &mut net.state,
            &interval,
            lr,
            t,
            data,
            &net.ema,
            &options.device,
        );
        log.push(line.clone());
        progress(Event::Log(line));
        if net.state.best_val_step == Some(done) {
            save_weights(&net.ema, &run.join(BEST_WEIGHTS), &provenance(options)?)?;
        }
        interval = Interval::new();
        if done.is_multiple_of(t.checkpoint_every) {
            // The log first: a run killed between the two resumes with its whole history
            // (lines past the checkpoint are dropped on resume).
            write_log(run, log)?;
            plot(run, log)?;
            checkpoint::save(run, config, &net.model, &net.optim, &net.ema, &net.state)?;
            saved_at = done;
        }
        let out_of_time = options
            .minutes
            .is_some_and(|m| session.elapsed().as_secs_f64() >= m * 60.0);
        if out_of_time {
            break;
        }
    }
    Ok((net, saved_at))
}

/// The log line of the steps in `interval`, the EMA's validation loss with it where due (and
/// the best one kept in `state`).
fn log_line(
    state: &mut RunState,
    interval: &Interval,
    lr: f64,
    t: &TrainConfig,
    data: &TrainingData,
    ema: &Dit,
    device: &Device,
) -> LogLine {
    let done = state.step;
    let val_loss = (done.is_multiple_of(t.val_every) || done == t.steps)
        .then(|| validation_loss(ema, &data.val_batches, device))
        .flatten();
    if let Some(v) = val_loss
        && state.best_val_loss.is_none_or(|b| v < b)
    {
        state.best_val_loss = Some(v);
        state.best_val_step = Some(done);
    }
    let steps = interval.steps as f64;
    LogLine {
        step: done,
        loss: interval.loss / steps,
        lr,
        grad_norm: interval.grad_norm / steps,
        samples_per_s: (interval.steps * t.batch) as f64
            / interval.started.elapsed().as_secs_f64().max(1e-9),
        wall_s: state.wall_s,
        val_loss,
    }
}

/// What made a run's weights: its configuration, the tensors' manifest, the commit.
fn provenance(options: &TrainOptions) -> Result<Provenance> {
    Ok(Provenance {
        config_sha256: files::sha256_file(&options.out.join("config.toml"))?.0,
        dataset_manifest_sha256: files::sha256_file(&options.data.join("manifest.json"))?.0,
        commit: COMMIT.to_string(),
    })
}

/// The run's outputs: the log and its plot, a last checkpoint where the steps ended between
/// two, the EMA weights shipped (the last, or with `keep_best` the best) with their
/// provenance, the reference batch of those weights and the summary.
fn finish(
    options: &TrainOptions,
    config: &RunConfig,
    data: &TrainingData,
    net: &Loaded,
    log: &[LogLine],
    saved_at: usize,
) -> Result<Summary> {
    let (t, run) = (&config.training, &options.out);
    let state = &net.state;
    write_log(run, log)?;
    plot(run, log)?;
    if saved_at != state.step {
        checkpoint::save(run, config, &net.model, &net.optim, &net.ema, state)?;
    }
    let best = run.join(BEST_WEIGHTS);
    let (shipped, model_step) = match state.best_val_step {
        Some(step) if t.keep_best && best.is_file() => (
            load_weights(&best, config, &run.join("config.toml"), &options.device)?,
            step,
        ),
        _ => (net.ema.clone(), state.step),
    };
    save_weights(
        &shipped,
        &run.join("model.safetensors"),
        &provenance(options)?,
    )?;
    let reference = reference_batch(&data.tensors, &data.train, &data.val, t, data.recipe);
    save_reference(
        &shipped,
        &reference,
        &run.join("reference.safetensors"),
        &options.device,
    )?;
    let summary = Summary {
        steps: state.step,
        parameters: net.model.parameters(),
        final_loss: log.last().map_or(f64::NAN, |l| l.loss),
        best_val_loss: state.best_val_loss,
        best_val_step: state.best_val_step,
        model_step,
        wall_s: state.wall_s,
        samples_per_s: (state.step * t.batch) as f64 / state.wall_s.max(1e-9),
        config: config.clone(),
    };
    let json = serde_json::to_vec_pretty(&summary).expect("the summary serializes");
    write_atomic(&run.join("summary.json"), &json)?;
    Ok(summary)
}

/// `preferred` when it has frames, else the first held-out split (in `dataset::Split::ALL`
/// order) that has: small datasets often leave the main test split empty.
fn held_out_split(tensors: &TrainingTensors, preferred: &str) -> Option<String> {
    let frames = |s: &str| tensors.manifest.splits.get(s).map_or(0, |i| i.frames);
    if frames(preferred) > 0 {
        return Some(preferred.to_string());
    }
    dataset::Split::ALL
        .into_iter()
        .filter(|s| *s != dataset::Split::Train)
        .map(dataset::Split::name)
        .find(|s| frames(s) > 0)
        .map(str::to_string)
}

/// Two held-out frames (training frames when there are none) at s = 0.25 and 0.75: the fixed
/// input of `reference.safetensors`.
fn reference_batch(
    tensors: &TrainingTensors,
    train: &Frames,
    val: &Frames,
    t: &TrainConfig,
    recipe: Recipe,
) -> Batch {
    let split = if val.is_empty() { train } else { val };
    let frames = [0, split.len() - 1];
    let mut rng = generator(t.seed, 3, 0);
    // The reference holds held-out conditions as they are, as prediction gives them.
    let recipe = Recipe {
        condition_noise: 0.0,
        ..recipe
    };
    Batch::new(tensors, split, &frames, &[0.25, 0.75], recipe, &mut rng)
}
