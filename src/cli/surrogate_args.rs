//! The surrogate's command-line flags: `train`, `predict`, `evaluate` (plain values, no I/O).

use std::path::PathBuf;

use clap::Args;
use surrogate::predict::{Guidance, Settings};

use super::SceneInputs;

/// How the surrogate's sampler runs: the flags `predict` and `evaluate` share.
#[derive(Debug, Args)]
pub struct SamplerArgs {
    /// Euler steps from noise to data (default: the model's, 1 for a regression model, 4
    /// for a flow model).
    #[arg(long)]
    pub steps: Option<usize>,
    /// Intersection guidance weight (0 turns it off; `evaluate`'s `model` rows use it, its
    /// `model_no_guidance` rows 0).
    #[arg(long, allow_hyphen_values = true, default_value_t = 5.0)]
    pub guidance: f64,
    /// Fraction of the steps done before guidance starts (default: the model's, 0 for a
    /// regression model, 0.5 for a flow model).
    #[arg(long, allow_hyphen_values = true)]
    pub guidance_start: Option<f64>,
    /// Guidance passes on the finished sample, without the network (default: the model's, 2
    /// for a regression model, 0 for a flow model).
    #[arg(long)]
    pub guidance_refine: Option<usize>,
    /// Seed of the sampler's noise.
    #[arg(long, default_value_t = 0)]
    pub seed: u64,
    /// Frames sampled together.
    #[arg(long, default_value_t = 16)]
    pub batch: usize,
    /// Samples drawn per frame, each from its own noise, and averaged (1 to 64).
    #[arg(long, default_value_t = 1)]
    pub draws: usize,
}

impl SamplerArgs {
    /// The sampler's settings: these flags over `defaults` (the model's).
    pub fn settings(&self, defaults: Settings) -> Settings {
        Settings {
            steps: self.steps.unwrap_or(defaults.steps),
            guidance: Guidance {
                weight: self.guidance,
                start: self.guidance_start.unwrap_or(defaults.guidance.start),
                refine: self.guidance_refine.unwrap_or(defaults.guidance.refine),
                ..Guidance::default()
            },
            seed: self.seed,
            batch: self.batch,
            draws: self.draws,
            ..defaults
        }
    }
}

#[derive(Debug, Args)]
pub struct EvaluateArgs {
    /// Trained model: a run folder, an ensemble folder (`ensemble.toml`), `builtin` (the shipped
    /// ensemble of two networks), `builtin-single` (its first network alone, faster) or `none`
    /// (baselines only).
    #[arg(long, default_value = "builtin")]
    pub model: String,
    /// Dataset folder (`synth --out`).
    #[arg(long)]
    pub data: PathBuf,
    /// Splits to score, comma-separated (those without sequences are skipped).
    #[arg(
        long,
        value_delimiter = ',',
        default_value = "test,test_garment,test_motion,test_shape,test_material,test_grid"
    )]
    pub splits: Vec<String>,
    #[command(flatten)]
    pub sampler: SamplerArgs,
    /// Baselines, comma-separated: lbs, lbs_nearest, floor, rest.
    #[arg(
        long,
        value_delimiter = ',',
        default_value = "lbs,lbs_nearest,floor,rest"
    )]
    pub baselines: Vec<String>,
    /// At most K sequences per split (the first K in the manifest's order).
    #[arg(long)]
    pub max_sequences: Option<usize>,
    /// SMPL-format .npz body model the dataset was made with (default: the default body).
    #[arg(long)]
    pub body_model: Option<PathBuf>,
    /// Write the scores here (`splits`, `sequences`, `model`, `settings`, `units`, ...).
    #[arg(long)]
    pub json: Option<PathBuf>,
    /// Write the report here: README.md, index.html, pictures; per-sequence results are
    /// cached in DIR/sequences and reused by a rerun with the same settings.
    #[arg(long)]
    pub report: Option<PathBuf>,
    /// Compute threads (default: all cores).
    #[arg(long)]
    pub threads: Option<usize>,
    /// Hide the progress bar.
    #[arg(long)]
    pub quiet: bool,
}

#[derive(Debug, Args)]
pub struct PairedArgs {
    /// The first evaluation (`evaluate --json`): the one compared against.
    pub a: PathBuf,
    /// The second evaluation, of the same recordings; differences are B minus A.
    pub b: PathBuf,
    /// Which method of each file to compare: `model`, `model_no_guidance` or a baseline.
    #[arg(long, default_value = "model")]
    pub method: String,
    /// Which metric: `E_v`, `E_c`, `E_CD_cm`, ... (any number each sequence reports).
    #[arg(long, default_value = "E_v")]
    pub metric: String,
    /// Write the rows here (`a`, `b`, `method`, `metric`, `rows`: `group`, `sequences`, `a`,
    /// `b`, `difference`, `sd`, `standard_error`, `b_lower`).
    #[arg(long)]
    pub json: Option<PathBuf>,
}

#[derive(Debug, Args)]
pub struct PredictArgs {
    /// Trained model: a run folder (`train --out`), an ensemble folder (`ensemble.toml`),
    /// `builtin` (the shipped ensemble of two networks) or `builtin-single` (its first network
    /// alone, faster).
    #[arg(long, default_value = "builtin")]
    pub model: String,
    #[command(flatten)]
    pub scene: SceneInputs,
    #[command(flatten)]
    pub sampler: SamplerArgs,
    /// Time shift of the step schedule (1: uniform; above 1 spends more steps at high noise).
    #[arg(long, allow_hyphen_values = true, default_value_t = 1.0)]
    pub shift: f64,
    /// Draw the initial noise per frame (default: one noise for the whole sequence, which
    /// keeps frames coherent).
    #[arg(long)]
    pub per_frame_noise: bool,
    /// After sampling, push vertices still inside the body out along its normal (D-Garment's
    /// post-process; off by default, reported separately).
    #[arg(long)]
    pub resolve_penetration: bool,
    /// Output recording (.mcap).
    #[arg(long)]
    pub out: PathBuf,
    /// Write every frame's garment (and body) as OBJ into this folder.
    #[arg(long)]
    pub obj_dir: Option<PathBuf>,
    /// Also record the body vertices of every frame (large).
    #[arg(long)]
    pub body_vertices: bool,
    /// Write the run's figures (`frames`, `finite`, `frames_per_s`, `wall_s`, `steps`,
    /// `guidance`, `batch`, `E_c_percent`, `max_penetration_m`, `vertices`, `model`, ...) here.
    #[arg(long)]
    pub json: Option<PathBuf>,
    /// Compute threads (default: all cores).
    #[arg(long)]
    pub threads: Option<usize>,
    /// Hide the progress bar.
    #[arg(long)]
    pub quiet: bool,
}

#[derive(Debug, Args)]
pub struct TrainArgs {
    /// Training tensors folder (`dataset tensors --out`).
    #[arg(long)]
    pub data: PathBuf,
    /// Run folder: `config.toml`, `log.jsonl`, `loss.png`, `checkpoint-<step>/`,
    /// `model.safetensors`, `reference.safetensors`, `summary.json`.
    #[arg(long)]
    pub out: PathBuf,
    /// Run configuration (TOML, `[model]` and `[training]` tables) over the defaults; see
    /// `--print-config`. With `--resume`, the run's own `config.toml` is the default.
    #[arg(long)]
    pub config: Option<PathBuf>,
    /// Optimizer steps of the whole run (`training.steps`).
    #[arg(long)]
    pub steps: Option<usize>,
    /// Stop after this many minutes (at the next log line, with a checkpoint); `--resume`
    /// continues.
    #[arg(long)]
    pub minutes: Option<f64>,
    /// Frames per step (`training.batch`).
    #[arg(long)]
    pub batch: Option<usize>,
    /// Seed of the weights, batches and noise (`training.seed`).
    #[arg(long)]
    pub seed: Option<u64>,
    /// Continue the run in `--out` from its last checkpoint.
    #[arg(long)]
    pub resume: bool,
    /// Print the resolved configuration (TOML) and exit.
    #[arg(long)]
    pub print_config: bool,
    /// Compute threads (default: all cores; 1 gives bit-identical reruns).
    #[arg(long)]
    pub threads: Option<usize>,
    /// No progress bar.
    #[arg(long)]
    pub quiet: bool,
}
