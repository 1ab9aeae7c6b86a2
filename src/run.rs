//! A garment run as the commands share it: the scene configuration resolved from its layers
//! (defaults, `--config` or `--config-from`, then flags), what it names loaded into a
//! [`Scene`], and the run recorded as MCAP (atomically, with optional OBJ frames, a progress
//! bar and a deadline).

use std::io::Write;
use std::path::Path;
use std::time::Instant;

use anyhow::{Context, Result, bail};
use indicatif::{ProgressBar, ProgressDrawTarget, ProgressStyle};
use serde_json::json;
use sim::SceneConfig;
use sim::recording::Recording;
use sim::run::Prepared;
use sim::scene::RunSummary;

use crate::cli::{SceneArgs, SceneInputs};
use crate::inputs;

/// The most compute threads (or synthesis jobs) a run may ask for.
pub const MAX_THREADS: usize = 1024;

/// Sets the compute threads of a `--threads` flag (all cores when absent).
pub fn set_threads(threads: Option<usize>) -> Result<()> {
    if let Some(threads) = threads {
        if !(1..=MAX_THREADS).contains(&threads) {
            bail!("--threads {threads}: 1 to {MAX_THREADS}");
        }
        rayon::ThreadPoolBuilder::new()
            .num_threads(threads)
            .build_global()
            .context("setting the thread count")?;
    }
    Ok(())
}

/// The configuration the flags ask for: the defaults, or a `--config` file, or the
/// configuration a `--config-from` recording carries, with every given flag over it. It is
/// checked once, by [`prepare`] (or [`print_config`]), before anything it names is loaded.
pub fn resolve_config(args: &SceneArgs) -> Result<SceneConfig> {
    let mut c = match &args.config {
        Some(path) => SceneConfig::load(path)?,
        None => base_config(&args.inputs)?,
    };
    apply_inputs(&mut c, &args.inputs)?;
    if let Some(v) = &args.model_alias {
        c.model = Some(v.display().to_string());
    }
    if let Some(v) = args.friction {
        c.friction = v;
    }
    if let Some(v) = args.substeps {
        c.solver.substeps = v;
    }
    if let Some(v) = args.iterations {
        c.solver.max_iterations = v;
    }
    if let Some(v) = args.acceleration {
        c.solver.acceleration = v;
    }
    if args.no_self_contact {
        c.solver.self_contact = false;
    }
    if let Some(v) = args.self_contact_distance {
        c.solver.self_contact_distance = v;
    }
    if let Some(v) = args.self_friction {
        c.solver.self_friction = v;
    }
    Ok(c)
}

/// The configuration of a scene's inputs alone (`predict`): the defaults or a `--config-from`
/// recording's, the flags over it (checked by [`prepare`]).
pub fn resolve_inputs(inputs: &SceneInputs) -> Result<SceneConfig> {
    let mut c = base_config(inputs)?;
    apply_inputs(&mut c, inputs)?;
    Ok(c)
}

/// The configuration a `--config-from` recording carries, else the defaults.
fn base_config(inputs: &SceneInputs) -> Result<SceneConfig> {
    match &inputs.config_from {
        Some(path) => Ok(Recording::scene_config(path)?),
        None => Ok(SceneConfig::default()),
    }
}

/// The scene-input flags over `c`.
fn apply_inputs(c: &mut SceneConfig, inputs: &SceneInputs) -> Result<()> {
    if let Some(v) = &inputs.garment {
        c.garment = v.clone();
    }
    if let Some(v) = &inputs.motion {
        c.motion = v.clone();
    }
    if let Some(v) = &inputs.body_model {
        c.model = Some(v.display().to_string());
    }
    if let Some(v) = &inputs.betas {
        c.betas = v.clone();
    }
    if let Some(v) = &inputs.material {
        c.material = c.material.with_overrides(v)?;
    }
    if let Some(v) = inputs.frames {
        c.frames = Some(v);
    }
    if let Some(v) = inputs.blend_frames {
        c.blend_frames = v;
    }
    if let Some(v) = inputs.settle_frames {
        c.settle_frames = v;
    }
    Ok(())
}

/// With `--print-config`: validates the configuration and prints it as TOML; returns whether
/// it did (the command then stops).
pub fn print_config(args: &SceneArgs, config: &SceneConfig) -> Result<bool> {
    if !args.print_config {
        return Ok(false);
    }
    config.validate()?;
    let mut stdout = std::io::stdout().lock();
    stdout.write_all(config.to_toml().as_bytes())?;
    stdout.flush()?;
    Ok(true)
}

/// Checks the configuration (the one check of its values), then loads what it names (body
/// model, garment, motion) and builds its scene.
pub fn prepare(config: SceneConfig) -> Result<Prepared> {
    let config = config.validated()?;
    let garment = config.garment.clone();
    let cache = sim::templates::cache_dir();
    Ok(Prepared::load(
        config,
        &cache,
        inputs::making_template(&garment),
    )?)
}

/// How a run shows itself and what it writes besides the recording.
#[derive(Debug, Clone, Copy, Default)]
pub struct RecordOptions<'a> {
    /// Write OBJ frames into this folder, every K-th frame.
    pub obj: Option<(&'a Path, usize)>,
    /// Hide the progress bar.
    pub quiet: bool,
    /// Stop with [`sim::Error::Deadline`] when the run is still going at this moment.
    pub deadline: Option<Instant>,
}

/// Runs a prepared scene into `out` (atomically), with a progress bar and OBJ frames as
/// `options` ask.
pub fn record(p: &Prepared, out: &Path, options: RecordOptions) -> Result<RunSummary> {
    let software = format!("dit-garment {}", env!("CARGO_PKG_VERSION"));
    let bar = frames_bar("simulating", p.scene.num_frames(), options.quiet);
    let summary = p.record_file(out, &software, options.deadline, |frame| {
        if let Some((dir, every)) = options.obj
            && frame.index % every.max(1) == 0
        {
            let body = &frame.body.vertices;
            sim::run::write_objs(
                dir,
                frame.index,
                &p.garment,
                frame.garment,
                body,
                p.model.faces(),
            )?;
        }
        bar.inc(1);
        Ok(())
    })?;
    bar.finish_and_clear();
    Ok(summary)
}

/// A progress bar of `len` items: `what [====>   ] pos/len UNIT (rest)`, where `rest` is an
/// indicatif template (`{per_sec}`, `{eta}`, `{msg}`, ...); hidden when `quiet`.
pub fn progress(what: &str, len: usize, unit: &str, rest: &str, quiet: bool) -> ProgressBar {
    let template = format!("{what} [{{bar:30}}] {{pos}}/{{len}} {unit} {rest}");
    let style = ProgressStyle::with_template(&template)
        .expect("the commands' templates are valid")
        .progress_chars("=> ");
    let bar = ProgressBar::new(len as u64).with_style(style);
    if quiet {
        bar.set_draw_target(ProgressDrawTarget::hidden());
    }
    bar
}

/// A progress bar over `frames` frames, labelled `what`; hidden when `quiet`.
pub fn frames_bar(what: &str, frames: usize, quiet: bool) -> ProgressBar {
    progress(what, frames, "frames", "({per_sec}, eta {eta})", quiet)
}

/// A progress bar for a GIF being drawn, shown from its first frame and cleared after its
/// last.
pub fn gif_progress() -> impl FnMut(usize, usize) {
    let mut bar: Option<ProgressBar> = None;
    move |done, total| {
        let bar = bar.get_or_insert_with(|| frames_bar("gif", total, false));
        bar.set_position(done as u64);
        if done == total {
            bar.finish_and_clear();
        }
    }
}

/// The machine-readable summary (keys checked by scripts): the run's numbers and where it
/// was recorded.
pub fn summary_json(s: &RunSummary, out: &Path) -> serde_json::Value {
    let mut summary = serde_json::to_value(s).expect("a run summary serializes");
    summary["recording"] = json!(out);
    summary
}
