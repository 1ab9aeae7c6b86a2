//! `dit-garment train`: the surrogate trained on training tensors, with a progress bar (loss,
//! samples/s, ETA), resumable from its checkpoints.

use anyhow::{Context, Result, bail};
use surrogate::burn::prelude::Device;
use surrogate::data::TrainingTensors;
use surrogate::run::RunConfig;
use surrogate::train::{Event, TrainOptions, train};

use crate::cli::TrainArgs;
use crate::run::{progress, set_threads};

/// The configuration the flags ask for: the defaults (or, resuming, the run's own
/// `config.toml`), then `--config`, then `--steps`, `--batch`, `--seed`.
fn resolve(args: &TrainArgs) -> Result<RunConfig> {
    let own = args.out.join("config.toml");
    let mut config = match (&args.config, args.resume && own.exists()) {
        (Some(path), _) => RunConfig::load(path)?,
        (None, true) => RunConfig::load_saved(&own)?,
        (None, false) => RunConfig::default(),
    };
    if let Some(steps) = args.steps {
        config.training.steps = steps;
    }
    if let Some(batch) = args.batch {
        config.training.batch = batch;
    }
    if let Some(seed) = args.seed {
        config.training.seed = seed;
    }
    Ok(config)
}

pub fn run(args: &TrainArgs) -> Result<()> {
    set_threads(args.threads)?;
    if let Some(m) = args.minutes
        && !(m.is_finite() && m > 0.0)
    {
        bail!("--minutes {m}: must be a positive number of minutes");
    }
    let mut config = resolve(args)?;
    let tensors = TrainingTensors::open(&args.data)
        .with_context(|| format!("reading the training tensors in {}", args.data.display()))?;
    config.fit_to(&tensors);
    config.validate()?;
    if args.print_config {
        say_part!("{}", config.to_toml());
        return Ok(());
    }
    drop(tensors);
    let options = TrainOptions {
        data: args.data.clone(),
        out: args.out.clone(),
        config,
        minutes: args.minutes,
        resume: args.resume,
        device: Device::flex(),
    };
    let steps = options.config.training.steps;
    let bar = progress("training", steps, "steps,", "{msg} (eta {eta})", args.quiet);
    let mut samples_per_s = 0.0;
    let mut last_val = None;
    let summary = train(&options, &mut |event| match event {
        Event::Started {
            step,
            steps,
            extended_from,
            parameters,
            train_frames,
            val_frames,
            val_split,
        } => {
            bar.set_length(steps as u64);
            bar.set_position(step as u64);
            bar.reset_eta();
            // A closed pipe here is met again by the run's last line, which reports it.
            let _ = bar.suspend(|| -> Result<()> {
                if let Some(before) = extended_from {
                    say!(
                        "extending the run from {before} to {steps} steps: the learning rate from step {step} on follows the {steps}-step schedule"
                    );
                }
                say!(
                    "training {parameters} parameters on {train_frames} frames ({val_frames} of {} for validation), steps {step}..{steps}",
                    val_split.as_deref().unwrap_or("no held-out split")
                );
                Ok(())
            });
        }
        Event::Step { step, loss } => {
            bar.set_position(step as u64);
            let val = last_val.map(|v: f64| format!(", val {v:.4}")).unwrap_or_default();
            bar.set_message(format!("loss {loss:.4}{val}, {samples_per_s:.1} samples/s"));
        }
        Event::Log(line) => {
            samples_per_s = line.samples_per_s;
            if line.val_loss.is_some() {
                last_val = line.val_loss;
            }
            // Without a terminal the bar is hidden, and `log.jsonl` is written only at
            // checkpoints: each log line is printed instead, so a run's output shows progress.
            if bar.is_hidden() && !args.quiet {
                let val = line
                    .val_loss
                    .map(|v| format!(", val {v:.4}"))
                    .unwrap_or_default();
                // A closed pipe here is met again by the run's last line, which reports it.
                let _ = (|| -> Result<()> {
                    say!(
                        "step {}/{steps}: loss {:.4}{val}, {:.2} samples/s",
                        line.step,
                        line.loss,
                        line.samples_per_s
                    );
                    Ok(())
                })();
            }
        }
    })
    .with_context(|| format!("training into {}", args.out.display()))?;
    bar.finish_and_clear();
    say!(
        "trained {} steps in {:.1} s ({:.2} samples/s): final loss {:.4}, best validation loss {}; weights of step {} in {}",
        summary.steps,
        summary.wall_s,
        summary.samples_per_s,
        summary.final_loss,
        match (summary.best_val_loss, summary.best_val_step) {
            (Some(v), Some(step)) => format!("{v:.4} (step {step})"),
            (Some(v), None) => format!("{v:.4}"),
            _ => "none".into(),
        },
        summary.model_step,
        args.out.join("model.safetensors").display()
    );
    Ok(())
}
