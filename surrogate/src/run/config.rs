//! A training run's configuration: the model (`[model]`) and the optimization (`[training]`),
//! one TOML file (`RUN/config.toml`, `train --config`, `train --print-config`) laid over the
//! defaults, every key named when it is unknown or bad.

use serde::{Deserialize, Serialize};

use crate::data::TrainingTensors;
use crate::error::{Error, Result, bad_value};
use crate::model::{DitConfig, Prediction};

/// How rectified-flow times are drawn during training.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum TimeSampling {
    /// sigmoid(N(mean, std)) (Sana's and SD3's choice: more weight mid-way).
    LogitNormal,
    /// U(0, 1).
    Uniform,
}

/// What the network is trained to do.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum Objective {
    /// Rectified flow: times drawn by `time_sampling`, sampled by Euler steps.
    Flow,
    /// Regression of the conditional mean: every sample at s = 1 (pure noise in, the clean
    /// map out), so one sampler step returns it. The conditional mean is what minimizes E_v.
    Regression,
}

/// The optimization.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct TrainConfig {
    /// Optimizer steps of the whole run (the learning-rate schedule spans them).
    pub steps: usize,
    /// Frames per step.
    pub batch: usize,
    /// Seeds the weights, the batches, the noise and the validation draws.
    pub seed: u64,
    /// Peak learning rate (AdamW).
    pub lr: f64,
    /// Decoupled weight decay (AdamW; burn's default is 1e-4, PyTorch's 1e-2).
    pub weight_decay: f64,
    /// AdamW epsilon (burn's default is 1e-5, PyTorch's 1e-8).
    pub adam_eps: f64,
    /// AdamW first-moment decay.
    pub beta1: f64,
    /// AdamW second-moment decay.
    pub beta2: f64,
    /// Steps of linear warm-up before the cosine decay to zero.
    pub warmup_steps: usize,
    /// Gradients are scaled down to this global L2 norm when larger (0: no clipping).
    pub grad_clip_norm: f64,
    /// Decay of the exponential moving average of the weights (the shipped weights).
    pub ema_decay: f64,
    /// Stochastic weight averaging (Izmailov et al. 2018) from this step on: the learning rate
    /// stays at its value there, and the shipped weights are the plain mean of every step's
    /// weights since instead of the EMA, averaging over the iterates a constant rate keeps
    /// apart rather than over the last, nearly still ones of a decay to zero. 0: off.
    pub swa_start: usize,
    /// Rectified flow or regression at s = 1.
    pub objective: Objective,
    /// Start the final linear and the cross-attention projections at zero.
    pub zero_init: bool,
    /// Set the target to zero outside the loss mask before noising (the sampler keeps its
    /// estimate zero there too), so the network never sees extrapolated texels as data.
    pub zero_outside: bool,
    /// Time sampling.
    pub time_sampling: TimeSampling,
    /// Mean of the logit-normal's normal.
    pub logit_mean: f64,
    /// Standard deviation of the logit-normal's normal.
    pub logit_std: f64,
    /// Loss weight of texels inside a chart, relative to texels only read back (outside the
    /// loss mask the weight is 0).
    pub inside_weight: f64,
    /// Steps between log lines (the logged loss is the mean over them).
    pub log_every: usize,
    /// Steps between validation losses (a multiple of `log_every`).
    pub val_every: usize,
    /// Held-out frames the validation loss averages over (evenly spaced in the split).
    pub val_frames: usize,
    /// The tensors' split validation frames come from (never trained on); when it has no
    /// frames, the first held-out split that has.
    pub val_split: String,
    /// Steps between checkpoints (a multiple of `log_every`).
    pub checkpoint_every: usize,
    /// With `model.previous_state`: the spread of the smooth noise laid on the previous
    /// frame's simulated target map (normalized units, the targets' std is 1), standing in
    /// for the model's own errors, which is what it gets at prediction.
    pub previous_noise: f64,
    /// With `model.previous_state`: the most frames the network is run on its own output
    /// before a training sample (0: the simulated previous frame with noise only). Each
    /// step unrolls a depth drawn from 0 to this, without gradients (`train/rollout.rs`).
    pub rollout: usize,
    /// The spread of Gaussian noise laid on every normalized condition value of a training
    /// sample (0: none; validation batches get none): blurs the pose a sample is given, so that
    /// a training sequence cannot be told by its conditions alone (issue 53, arm a26).
    pub condition_noise: f64,
    /// The fraction of each block's attention, cross-attention and Mix-FFN outputs zeroed
    /// (the rest scaled by 1 / (1 - rate)) while training (0: none; validation and sampling
    /// never drop): a regularizer for a network that learns its training sequences by heart
    /// (issue 53, arm a31).
    pub dropout: f64,
    /// Ship the EMA weights of the lowest validation loss (`RUN/best.safetensors`, the
    /// training data's own held-out split) as `model.safetensors` instead of the last step's:
    /// early stopping that never looks at a set used for choosing arms.
    pub keep_best: bool,
}

impl Default for TrainConfig {
    fn default() -> Self {
        Self {
            steps: 3000,
            batch: 8,
            seed: 0,
            lr: 1e-3,
            weight_decay: 1e-2,
            adam_eps: 1e-8,
            beta1: 0.9,
            beta2: 0.999,
            warmup_steps: 100,
            grad_clip_norm: 1.0,
            ema_decay: 0.999,
            swa_start: 0,
            objective: Objective::Regression,
            zero_init: true,
            zero_outside: true,
            time_sampling: TimeSampling::Uniform,
            logit_mean: 0.0,
            logit_std: 1.0,
            inside_weight: 1.0,
            log_every: 10,
            val_every: 100,
            val_frames: 64,
            val_split: "test".into(),
            checkpoint_every: 100,
            previous_noise: 0.3,
            rollout: 0,
            condition_noise: 0.0,
            dropout: 0.0,
            keep_best: false,
        }
    }
}

impl TrainConfig {
    /// Names the first bad value.
    pub fn validate(&self) -> Result<()> {
        let bad = |key: &str, value: &dyn std::fmt::Display, expected: &str| {
            Err(bad_value(&format!("training.{key}"), value, expected))
        };
        let positive = |v: f64| v.is_finite() && v > 0.0;
        if self.steps == 0 || self.steps > 100_000_000 {
            return bad("steps", &self.steps, "must be 1 to 1e8");
        }
        if self.batch == 0 || self.batch > 4096 {
            return bad("batch", &self.batch, "must be 1 to 4096");
        }
        if !positive(self.lr) || self.lr > 1.0 {
            return bad("lr", &self.lr, "must be in (0, 1]");
        }
        if !(self.weight_decay.is_finite() && (0.0..1.0).contains(&self.weight_decay)) {
            return bad("weight_decay", &self.weight_decay, "must be in [0, 1)");
        }
        if !positive(self.adam_eps) {
            return bad("adam_eps", &self.adam_eps, "must be a positive number");
        }
        for (key, v) in [
            ("beta1", self.beta1),
            ("beta2", self.beta2),
            ("ema_decay", self.ema_decay),
        ] {
            if !(v.is_finite() && (0.0..1.0).contains(&v)) {
                return bad(key, &v, "must be in [0, 1)");
            }
        }
        if !(self.grad_clip_norm.is_finite() && self.grad_clip_norm >= 0.0) {
            return bad(
                "grad_clip_norm",
                &self.grad_clip_norm,
                "must be 0 (off) or positive",
            );
        }
        if !self.logit_mean.is_finite() {
            return bad("logit_mean", &self.logit_mean, "must be finite");
        }
        if !positive(self.logit_std) {
            return bad("logit_std", &self.logit_std, "must be a positive number");
        }
        if !(self.inside_weight.is_finite() && self.inside_weight >= 0.0) {
            return bad(
                "inside_weight",
                &self.inside_weight,
                "must be 0 or positive",
            );
        }
        if self.log_every == 0 {
            return bad("log_every", &self.log_every, "must be at least 1");
        }
        for (key, v) in [
            ("val_every", self.val_every),
            ("checkpoint_every", self.checkpoint_every),
        ] {
            if v == 0 || v % self.log_every != 0 {
                return bad(key, &v, "must be a positive multiple of log_every");
            }
        }
        if self.swa_start >= self.steps {
            return bad(
                "swa_start",
                &self.swa_start,
                "must be 0 (off) or below steps",
            );
        }
        if !(self.previous_noise.is_finite() && (0.0..=10.0).contains(&self.previous_noise)) {
            return bad("previous_noise", &self.previous_noise, "must be in [0, 10]");
        }
        if !(self.condition_noise.is_finite() && (0.0..=10.0).contains(&self.condition_noise)) {
            return bad(
                "condition_noise",
                &self.condition_noise,
                "must be in [0, 10]",
            );
        }
        if !(self.dropout.is_finite() && (0.0..=0.5).contains(&self.dropout)) {
            return bad("dropout", &self.dropout, "must be in [0, 0.5]");
        }
        if self.rollout > 16 {
            return bad("rollout", &self.rollout, "must be at most 16 frames");
        }
        if self.val_frames > 100_000 {
            return bad("val_frames", &self.val_frames, "must be at most 100000");
        }
        Ok(())
    }

    /// The learning rate of `step` (0-based): linear warm-up, then cosine decay to zero at
    /// `steps`, held from `swa_start` on where that is set.
    pub fn lr_at(&self, step: usize) -> f64 {
        let step = match self.swa_start {
            0 => step,
            start => step.min(start),
        };
        if step < self.warmup_steps {
            return self.lr * (step + 1) as f64 / self.warmup_steps as f64;
        }
        let span = (self.steps - self.warmup_steps.min(self.steps)).max(1) as f64;
        let progress = ((step - self.warmup_steps) as f64 / span).min(1.0);
        self.lr * 0.5 * (1.0 + (std::f64::consts::PI * progress).cos())
    }
}

/// `RUN/config.toml`: the model and its training.
#[derive(Debug, Clone, Default, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct RunConfig {
    /// The network.
    pub model: DitConfig,
    /// The optimization.
    pub training: TrainConfig,
}

/// The most memory a training batch's activations may take, estimated before any
/// allocation ([`crate::model::DitConfig::activation_bytes_per_sample`]).
const MAX_ACTIVATION_BYTES: f64 = 16.0 * GIB;
const GIB: f64 = (1u64 << 30) as f64;

impl RunConfig {
    /// Both halves checked.
    pub fn validate(&self) -> Result<()> {
        self.model.validate()?;
        self.training.validate()?;
        let rollout = self.training.rollout;
        if rollout > 0 && !self.model.previous_state {
            return Err(bad_value(
                "training.rollout",
                rollout,
                "needs model.previous_state = true (it unrolls the previous-state input)",
            ));
        }
        let one_step = self.training.objective == Objective::Regression
            && self.model.prediction == Prediction::Data;
        if rollout > 0 && !one_step {
            return Err(bad_value(
                "training.rollout",
                rollout,
                "needs objective = \"regression\" and prediction = \"x0\" (an unrolled frame is \
                 one network call)",
            ));
        }
        let bytes = self.training.batch as f64 * self.model.activation_bytes_per_sample() as f64;
        if bytes > MAX_ACTIVATION_BYTES {
            return Err(bad_value(
                "training.batch",
                self.training.batch,
                &format!(
                    "needs about {:.1} GiB of activations with this network; at most {:.0} GiB \
                     (a smaller batch or network)",
                    bytes / GIB,
                    MAX_ACTIVATION_BYTES / GIB
                ),
            ));
        }
        Ok(())
    }

    /// As TOML.
    pub fn to_toml(&self) -> String {
        toml::to_string(self).expect("a run configuration serializes as TOML")
    }

    /// Parses TOML over the defaults; `source` names it in errors. Not validated.
    pub fn from_toml(text: &str, source: &str) -> Result<Self> {
        let defaults = Self::default();
        sim::config::toml_over_defaults(text, &defaults, &defaults).map_err(|message| {
            Error::Config {
                path: source.to_string(),
                message,
            }
        })
    }

    /// Reads a file over the defaults.
    pub fn load(path: &std::path::Path) -> Result<Self> {
        Self::from_toml(&read_text(path)?, &path.display().to_string())
    }

    /// Reads the configuration a run saved (`RUN/config.toml`, a checkpoint's). Saved files
    /// hold every key, so one without `model.prediction` was written before the key existed,
    /// by a velocity model.
    pub fn load_saved(path: &std::path::Path) -> Result<Self> {
        let text = read_text(path)?;
        let mut config = Self::from_toml(&text, &path.display().to_string())?;
        let table = text.parse::<toml::Table>().ok();
        let has = |section: &str, key: &str| {
            table
                .as_ref()
                .and_then(|t| t.get(section)?.get(key).cloned())
                .is_some()
        };
        let has_key = |key: &str| has("model", key);
        let has_training_key = |key: &str| has("training", key);
        if !has_key("prediction") {
            config.model.prediction = crate::model::Prediction::Velocity;
        }
        if !has_key("body_inputs") {
            config.model.body_inputs = false;
        }
        if !has_training_key("objective") {
            // Runs made before these keys existed: rectified flow with the old recipe.
            config.training.objective = Objective::Flow;
            config.training.zero_init = false;
            config.training.zero_outside = false;
        }
        Ok(config)
    }

    /// Sets what the tensors decide (resolution, condition length, target).
    pub fn fit_to(&mut self, tensors: &TrainingTensors) {
        let m = &tensors.manifest;
        self.model.resolution = m.resolution;
        self.model.condition_dim = m.condition_dim;
        self.model.target = m.target;
    }

    /// The first key whose value differs from `other`'s, as `key = here (there)`.
    pub fn first_difference(&self, other: &Self) -> Option<String> {
        let (a, b) = (
            toml::Table::try_from(self).ok()?,
            toml::Table::try_from(other).ok()?,
        );
        for (section, va) in &a {
            let (Some(ta), Some(tb)) = (va.as_table(), b.get(section).and_then(|v| v.as_table()))
            else {
                continue;
            };
            for (key, x) in ta {
                let y = tb.get(key);
                if y != Some(x) {
                    let y = y.map(|y| y.to_string()).unwrap_or_else(|| "absent".into());
                    return Some(format!("{section}.{key} = {x} here, {y} there"));
                }
            }
        }
        None
    }

    /// What keeps `self` from resuming the run saved as `saved`: every difference but a
    /// larger `training.steps`, which extends the run (the learning rate's schedule from the
    /// resumed step on is then the longer run's), and `training.keep_best`, which changes
    /// only which weights the finished run ships (`best.safetensors` is kept either way).
    pub fn resume_difference(&self, saved: &Self) -> Option<String> {
        let mut extended = saved.clone();
        if self.training.steps > saved.training.steps {
            extended.training.steps = self.training.steps;
        }
        extended.training.keep_best = self.training.keep_best;
        self.first_difference(&extended)
    }
}

fn read_text(path: &std::path::Path) -> Result<String> {
    Ok(files::read_to_string(
        path,
        files::limits::TEXT,
        "run configuration",
    )?)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A batch whose activations would not fit is refused from the configuration alone; the
    /// shipped recipe's batch is far inside the bound.
    #[test]
    fn a_batch_too_large_for_memory_is_refused_before_training() {
        let mut c = RunConfig::default();
        c.training.batch = 32;
        assert!(c.validate().is_ok());
        c.training.batch = 4096;
        let err = c.validate().unwrap_err().to_string();
        assert!(
            err.starts_with("training.batch = 4096: needs about"),
            "{err}"
        );
    }

    #[test]
    fn unknown_keys_and_bad_values_are_named() {
        let err = RunConfig::from_toml("[model]\nwidht = 64\n", "m.toml").unwrap_err();
        assert!(err.to_string().contains("m.toml") && err.to_string().contains("model.widht"));
        let c = RunConfig::from_toml("[training]\nlr = -1.0\n", "m.toml").unwrap();
        assert_eq!(
            c.validate().unwrap_err().to_string(),
            "training.lr = -1: must be in (0, 1]"
        );
        let c = RunConfig::from_toml("[training]\ncondition_noise = -0.1\n", "m.toml").unwrap();
        assert_eq!(
            c.validate().unwrap_err().to_string(),
            "training.condition_noise = -0.1: must be in [0, 10]"
        );
        let c = RunConfig::from_toml("[training]\ndropout = 0.6\n", "m.toml").unwrap();
        assert_eq!(
            c.validate().unwrap_err().to_string(),
            "training.dropout = 0.6: must be in [0, 0.5]"
        );
        let c = RunConfig::from_toml("[model]\nwidth = 64\nheads = 2\n", "m.toml").unwrap();
        assert_eq!(c.model.prediction, crate::model::Prediction::Data);
        assert_eq!(c.model.width, 64);
        assert_eq!(c.training, TrainConfig::default());
        let d = c.first_difference(&RunConfig::default()).unwrap();
        assert_eq!(d, "model.heads = 2 here, 4 there");
    }

    #[test]
    fn resuming_may_extend_the_steps_and_choose_the_shipped_weights_and_change_nothing_else() {
        let saved = RunConfig::default();
        let mut longer = saved.clone();
        longer.training.steps = saved.training.steps + 100;
        assert_eq!(longer.resume_difference(&saved), None);
        let mut shorter = saved.clone();
        shorter.training.steps = saved.training.steps - 1;
        let d = shorter.resume_difference(&saved).unwrap();
        assert!(d.starts_with("training.steps"), "{d}");
        let mut other = longer.clone();
        other.training.lr *= 2.0;
        let d = other.resume_difference(&saved).unwrap();
        assert!(d.starts_with("training.lr"), "{d}");
        let mut best = longer.clone();
        best.training.keep_best = !saved.training.keep_best;
        assert_eq!(best.resume_difference(&saved), None);
    }

    /// A run saved before `model.prediction` existed is a velocity model; a saved file with
    /// the key keeps it.
    #[test]
    fn a_saved_configuration_without_the_prediction_key_is_a_velocity_model() {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("config.toml");
        let full = RunConfig::default().to_toml();
        assert!(full.contains("prediction = \"x0\""), "{full}");
        std::fs::write(&path, &full).unwrap();
        assert_eq!(
            RunConfig::load_saved(&path).unwrap().model.prediction,
            crate::model::Prediction::Data
        );
        let old: String = full
            .lines()
            .filter(|l| !l.starts_with("prediction"))
            .map(|l| format!("{l}\n"))
            .collect();
        std::fs::write(&path, old).unwrap();
        assert_eq!(
            RunConfig::load_saved(&path).unwrap().model.prediction,
            crate::model::Prediction::Velocity
        );
        // A user's partial file takes the default.
        assert_eq!(
            RunConfig::load(&path).unwrap().model.prediction,
            crate::model::Prediction::Data
        );
    }

    #[test]
    fn the_schedule_warms_up_then_decays_to_zero() {
        let t = TrainConfig {
            steps: 110,
            warmup_steps: 10,
            ..TrainConfig::default()
        };
        let t = TrainConfig { lr: 1e-4, ..t };
        assert!((t.lr_at(0) - 1e-5).abs() < 1e-12);
        assert!((t.lr_at(9) - 1e-4).abs() < 1e-12);
        assert!((t.lr_at(10) - 1e-4).abs() < 1e-12);
        assert!((t.lr_at(60) - 5e-5).abs() < 1e-12);
        assert!(t.lr_at(110) < 1e-12);
        let averaged = TrainConfig {
            swa_start: 60,
            ..t.clone()
        };
        assert_eq!(averaged.lr_at(9), t.lr_at(9));
        assert_eq!(averaged.lr_at(60), t.lr_at(60));
        assert_eq!(averaged.lr_at(109), t.lr_at(60));
    }

    #[test]
    fn swa_must_start_before_the_end() {
        let t = TrainConfig {
            steps: 100,
            swa_start: 100,
            ..TrainConfig::default()
        };
        assert_eq!(
            t.validate().unwrap_err().to_string(),
            "training.swa_start = 100: must be 0 (off) or below steps"
        );
        assert!(TrainConfig { swa_start: 99, ..t }.validate().is_ok());
    }
}
