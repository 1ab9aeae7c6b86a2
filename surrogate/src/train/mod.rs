//! Training with rectified flow: z_s = (1 - s) z0 + s eps, the network predicts z0 or the
//! velocity eps - z0 (`model.prediction`; the standard interpolation, the paper's
//! DDPM-schedule formula is not rectified flow, docs/SURROGATE.md), AdamW with warm-up and cosine decay, global-norm clipping, an EMA
//! of the weights, a fixed validation set, checkpoints every K steps and exact resume.
//!
//! A run folder holds `config.toml`, `tensors.json` (the manifest of the tensors trained on:
//! what sampling needs of the data), `log.jsonl`, `loss.png`, `checkpoint-<step>/`,
//! `model.safetensors` (EMA), `reference.safetensors` and `summary.json`, each written
//! through a temporary name.

mod batch;
pub(crate) mod checkpoint;
mod optim;
mod reference;

use std::path::{Path, PathBuf};
use std::time::Instant;

use burn::optim::GradientsParams;
use burn::prelude::*;
use serde::{Deserialize, Serialize};

pub use batch::{Batch, Recipe, validation_batches};
pub use checkpoint::RunState;
use files::write_atomic;
pub use optim::{average_decay, clip_global_norm, ema_decay, update_ema};
pub use reference::save_reference;

use crate::data::TrainingTensors;
use crate::error::{Error, Result, file_error};
use crate::model::Dit;
use crate::noise::generator;
use crate::run::{COMMIT, Provenance, RunConfig, TENSORS_MANIFEST, TrainConfig, save_weights};

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

/// Trains (or resumes) a run; `progress` hears every step and log line.
pub fn train(options: &TrainOptions, progress: &mut dyn FnMut(Event)) -> Result<Summary> {
    let tensors = TrainingTensors::open(&options.data)?;
    let mut config = options.config.clone();
    config.fit_to(&tensors);
    config.validate()?;
    let (wanted, stored) = (
        config.model.body_channels(),
        tensors.manifest.body_channels(),
    );
    if wanted > stored {
        return Err(Error::Config {
            path: "the training configuration".into(),
            message: format!(
                "the model takes {wanted} body input channels (model.body_inputs, model.body_nearest), but the tensors in {} have {stored} (body inputs need the lbs_residual target, the nearest-body ones `dataset tensors --body-nearest`): remake them or turn the keys off",
                options.data.display()
            ),
        });
    }
    if config.model.previous_state && tensors.manifest.every != 1 {
        return Err(Error::Config {
            path: "the training configuration".into(),
            message: format!(
                "model.previous_state needs every frame of a sequence, but the tensors in {} keep every {}th (remake them without --every)",
                options.data.display(),
                tensors.manifest.every
            ),
        });
    }
    let run = &options.out;
    let config_path = run.join("config.toml");
    let mut extended_from = None;
    if options.resume {
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
        // Refused here, before a file is written, if it cannot continue.
        checkpoint::resumable(run, &config)?;
    } else if config_path.exists() || run.join("checkpoint.json").exists() {
        return Err(file_error(
            run,
            "already holds a training run (pass --resume to continue it, or choose a new folder)",
        ));
    }
    std::fs::create_dir_all(run).map_err(|e| file_error(run, e))?;
    write_atomic(&config_path, config.to_toml().as_bytes())?;
    // What sampling needs of the data (normalization, condition layout, target, frames).
    let manifest = serde_json::to_vec_pretty(&tensors.manifest).map_err(|e| file_error(run, e))?;
    write_atomic(&run.join(TENSORS_MANIFEST), &manifest)?;

    let t = &config.training;
    let train_frames = tensors.frames("train")?;
    if train_frames.is_empty() {
        return Err(file_error(&options.data, "has no training frames"));
    }
    let val_split = held_out_split(&tensors, &t.val_split);
    let val_frames = match &val_split {
        Some(split) => tensors.frames(split)?,
        None => crate::data::Frames::default(),
    };
    let recipe = Recipe::new(&config.model, t);
    let val_batches = validation_batches(&tensors, &val_frames, t, recipe);

    let plain = &options.device;
    let device = plain.clone().autodiff();
    device.seed(t.seed);
    let loaded = if options.resume {
        checkpoint::load(run, &config, &device)?
    } else {
        None
    };
    let (mut model, mut optim, mut ema, mut state) = match loaded {
        Some(l) => (l.model, l.optim, l.ema, l.state),
        None => {
            let mut model = Dit::new(&config.model, &device);
            if t.zero_init {
                model = model.zero_output_layers();
            }
            let ema = model.valid();
            let state = RunState {
                step: 0,
                wall_s: 0.0,
                best_val_loss: None,
            };
            (model, checkpoint::optimizer(t), ema, state)
        }
    };
    let mut log = read_log(run, state.step)?;
    let parameters = model.parameters();
    progress(Event::Started {
        step: state.step,
        steps: t.steps,
        extended_from,
        parameters,
        train_frames: train_frames.len(),
        val_frames: val_batches.iter().map(|b| b.size).sum(),
        val_split: val_split.clone(),
    });

    let session = Instant::now();
    let wall_before = state.wall_s;
    let (mut loss_sum, mut norm_sum, mut count, mut interval) = (0.0, 0.0, 0usize, Instant::now());
    let mut saved_at = state.step;
    while state.step < t.steps {
        let step = state.step;
        let batch = Batch::training(&tensors, &train_frames, t, recipe, step);
        let (noisy, position, mask, time, conditions) = batch.inputs(&device);
        let loss = batch.loss(model.forward(noisy, position, mask, time, conditions));
        let loss_value = f64::from(loss.clone().into_scalar::<f32>());
        if !loss_value.is_finite() {
            return Err(Error::Diverged {
                step: step + 1,
                loss: loss_value,
                config: config_path.display().to_string(),
            });
        }
        let mut grads = GradientsParams::from_grads(loss.backward(), &model);
        let grad_norm = clip_global_norm(&model, &mut grads, t.grad_clip_norm);
        let lr = t.lr_at(step);
        model = optim.step(lr, model, grads);
        ema = update_ema(ema, &model, average_decay(t, step));
        state.step += 1;
        state.wall_s = wall_before + session.elapsed().as_secs_f64();
        (loss_sum, norm_sum, count) = (loss_sum + loss_value, norm_sum + grad_norm, count + 1);
        progress(Event::Step {
            step: state.step,
            loss: loss_value,
        });
        let done = state.step;
        if done % t.log_every == 0 || done == t.steps {
            let val_loss = (done % t.val_every == 0 || done == t.steps)
                .then(|| validation_loss(&ema, &val_batches, plain))
                .flatten();
            if let Some(v) = val_loss {
                state.best_val_loss = Some(state.best_val_loss.map_or(v, |b: f64| b.min(v)));
            }
            let line = LogLine {
                step: done,
                loss: loss_sum / count as f64,
                lr,
                grad_norm: norm_sum / count as f64,
                samples_per_s: (count * t.batch) as f64
                    / interval.elapsed().as_secs_f64().max(1e-9),
                wall_s: state.wall_s,
                val_loss,
            };
            log.push(line.clone());
            progress(Event::Log(line));
            (loss_sum, norm_sum, count, interval) = (0.0, 0.0, 0, Instant::now());
            if done % t.checkpoint_every == 0 {
                // The log first: a run killed between the two resumes with its whole history
                // (lines past the checkpoint are dropped on resume).
                write_log(run, &log)?;
                plot(run, &log)?;
                checkpoint::save(run, &config, &model, &optim, &ema, &state)?;
                saved_at = done;
            }
            let out_of_time = options
                .minutes
                .is_some_and(|m| session.elapsed().as_secs_f64() >= m * 60.0);
            if out_of_time {
                break;
            }
        }
    }
    write_log(run, &log)?;
    plot(run, &log)?;
    if saved_at != state.step {
        checkpoint::save(run, &config, &model, &optim, &ema, &state)?;
    }
    let provenance = Provenance {
        config_sha256: files::sha256_file(&config_path)?.0,
        dataset_manifest_sha256: files::sha256_file(&options.data.join("manifest.json"))?.0,
        commit: COMMIT.to_string(),
    };
    save_weights(&ema, &run.join("model.safetensors"), &provenance)?;
    let reference = reference_batch(&tensors, &train_frames, &val_frames, t, recipe);
    save_reference(&ema, &reference, &run.join("reference.safetensors"), plain)?;
    let summary = Summary {
        steps: state.step,
        parameters,
        final_loss: log.last().map_or(f64::NAN, |l| l.loss),
        best_val_loss: state.best_val_loss,
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
    train: &crate::data::Frames,
    val: &crate::data::Frames,
    t: &TrainConfig,
    recipe: Recipe,
) -> Batch {
    let split = if val.is_empty() { train } else { val };
    let frames = [0, split.len() - 1];
    let mut rng = generator(t.seed, 3, 0);
    Batch::new(tensors, split, &frames, &[0.25, 0.75], recipe, &mut rng)
}
