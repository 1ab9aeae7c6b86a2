//! Command-line flags (plain values, no I/O); `commands` turns them into runs.

use std::path::PathBuf;

use clap::{Args, Parser, Subcommand};

/// Garment dynamics on SMPL-compatible bodies: bodies and motions today; the projective-dynamics
/// ground-truth engine and the DiT-Garment surrogate build on them.
///
/// Units everywhere: metres, seconds, radians (axis-angle); y up, the body facing +z.
#[derive(Debug, Parser)]
#[command(name = "dit-garment", version, about, long_about)]
pub struct Cli {
    #[command(subcommand)]
    pub command: Command,
}

#[derive(Debug, Subcommand)]
pub enum Command {
    /// Run the main job on built-in defaults: the default body through the built-in `walk`
    /// motion, written as an MCAP sequence, OBJ frames and a JSON summary.
    Demo(DemoArgs),
    /// Pose a body (default body or an SMPL .npz model) and write it as OBJ in the model's
    /// vertex order.
    Body(BodyArgs),
    /// List, inspect and export motions (built-in procedural motions or AMASS .npz files).
    Motions {
        #[command(subcommand)]
        command: MotionsCommand,
    },
}

#[derive(Debug, Args)]
pub struct DemoArgs {
    /// Output folder (created if missing).
    #[arg(long)]
    pub out: PathBuf,
    /// Motion to use: a built-in name (with optional `:speed=..,amplitude=..,duration=..`).
    #[arg(long, default_value = "walk")]
    pub motion: String,
    /// Write an OBJ of every K-th frame (0 = none).
    #[arg(long, default_value_t = 15)]
    pub obj_every: usize,
    /// Also write the numbers (frames, fps, height, timing) to this JSON file.
    #[arg(long)]
    pub json: Option<PathBuf>,
}

/// Where the body comes from and its shape.
#[derive(Debug, Args)]
pub struct ModelArgs {
    /// SMPL-format .npz model file (SMPL_NEUTRAL.npz ...); the licence-free default body if
    /// omitted.
    #[arg(long)]
    pub model: Option<PathBuf>,
}

#[derive(Debug, Args)]
pub struct BodyArgs {
    /// Output OBJ file.
    #[arg(long)]
    pub out: Option<PathBuf>,
    #[command(flatten)]
    pub model: ModelArgs,
    /// JSON with `betas` (any length; extra ones ignored), `pose` (72 axis-angle values,
    /// radians: global_orient then body_pose) and `transl` (3 values, metres); all optional.
    #[arg(long)]
    pub params: Option<PathBuf>,
    /// Take the pose and translation from this motion (built-in name or AMASS .npz) ...
    #[arg(long, requires = "frame")]
    pub motion: Option<String>,
    /// ... at this frame (30 fps frames, from 0).
    #[arg(long, requires = "motion")]
    pub frame: Option<usize>,
    /// Write `vertices`, `faces`, `boundary_edges`, `height_m` (and more) to this JSON file.
    #[arg(long)]
    pub json: Option<PathBuf>,
}

#[derive(Debug, Subcommand)]
pub enum MotionsCommand {
    /// List the built-in motions: name, frames, duration and what the body does.
    List {
        /// Also write the list as a JSON array (`name`, `frames`, `fps`, ...).
        #[arg(long)]
        json: Option<PathBuf>,
    },
    /// Describe one motion: frames, rate, duration, root travel, range of each joint.
    Show {
        /// Built-in name (optionally `name:speed=..,amplitude=..,duration=..`) or AMASS .npz.
        motion: String,
        #[command(flatten)]
        model: ModelArgs,
        /// Also write the numbers to this JSON file.
        #[arg(long)]
        json: Option<PathBuf>,
    },
    /// Export a motion as an MCAP sequence with body poses, joints and vertices per frame.
    Export {
        /// Built-in name (optionally with parameters) or AMASS .npz file.
        motion: String,
        /// Output .mcap file.
        #[arg(long)]
        out: PathBuf,
        #[command(flatten)]
        model: ModelArgs,
        /// Shape coefficients, comma-separated (default: zeros).
        #[arg(long, value_delimiter = ',', allow_hyphen_values = true)]
        betas: Vec<f64>,
        /// Frames blending from the canonical A-pose into the first frame (0 = none).
        #[arg(long, default_value_t = 0)]
        blend_frames: usize,
        /// Frames holding the first frame after the blend.
        #[arg(long, default_value_t = 0)]
        settle_frames: usize,
        /// Also write the numbers (frames, vertices, bytes) to this JSON file.
        #[arg(long)]
        json: Option<PathBuf>,
    },
}
