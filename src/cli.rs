//! Command-line flags (plain values, no I/O); `commands` turns them into runs.

use std::path::PathBuf;

use clap::{Args, Parser, Subcommand};

mod garments_args;
mod surrogate_args;
pub use garments_args::GarmentsCommand;
pub use surrogate_args::{EvaluateArgs, PairedArgs, PredictArgs, TrainArgs};

/// Garment dynamics on SMPL-compatible bodies: a projective-dynamics cloth engine with exact
/// frictional contact (the ground truth), and DiT-Garment, a diffusion transformer in UV space
/// trained on its data to pose garments directly.
///
/// Start with `demo --out DIR`: the engine simulates the default skirt through `walk`, the
/// shipped surrogate predicts the same sequence, and the two are compared. Datasets: `synth`,
/// `dataset`; the surrogate: `dataset tensors`, `train`, `predict`, `evaluate`.
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
    /// Run the main job on built-in defaults: a held-out library t-shirt (`vneck_tee`, a design
    /// the shipped surrogate never saw) on the default body through the built-in `walk`
    /// motion, simulated by the engine and predicted by the shipped surrogate, compared (MCAP recordings, OBJ frames, pictures, a viewer page, a JSON
    /// summary).
    Demo(DemoArgs),
    /// Simulate a garment on a body through a motion and record the sequence as MCAP.
    Simulate(SimulateArgs),
    /// The standard drape scene of cloth benchmarks (a 1 m cloth dropped onto a 0.3 m sphere for
    /// 2 s), timed and measured with the keys Newton, MuJoCo and Taichi runs of the same scene
    /// report (docs/BENCHMARKS.md has the side-by-side figures).
    DrapeBench(DrapeBenchArgs),
    /// Run the physics regression suite: one row per scenario (expected, measured,
    /// tolerance, pass).
    Regress(RegressArgs),
    /// Score recording B against recording A (ground truth, same template) with the paper's
    /// metrics, every 5th frame.
    Compare(CompareArgs),
    /// Draw a recording's frames as PNG pictures (garment on body, shaded, outlined), a
    /// contact sheet of them, and optionally an animated GIF; no GPU or display needed.
    Render(RenderArgs),
    /// Write one self-contained HTML page (WebGL, no network) that plays one or two recordings
    /// side by side, synchronized, with an orbit camera.
    View(ViewArgs),
    /// Synthesize a dataset from a TOML spec: sequences in parallel, quality gates, MCAP files
    /// and a JSON Lines manifest; resumable, sharded on Slurm or Kubernetes.
    Synth(SynthArgs),
    /// Check, summarize and merge datasets written by `synth`.
    Dataset {
        #[command(subcommand)]
        command: DatasetCommand,
    },
    /// Pose a body (default body or an SMPL .npz model) and write it as OBJ in the model's
    /// vertex order.
    Body(BodyArgs),
    /// List, inspect and export motions (built-in procedural motions, AMASS .npz files, BVH
    /// motion capture).
    Motions {
        #[command(subcommand)]
        command: MotionsCommand,
    },
    /// Garment templates: the design library, sewing patterns (GarmentCode JSON) sewn and
    /// draped into templates, and mesh checks.
    Garments {
        #[command(subcommand)]
        command: GarmentsCommand,
    },
    /// The surrogate's UV geometry images of a template or a recording: position map, mask,
    /// target maps and (for a recording) the round-trip floor, the best any UV model can do.
    Uv(UvArgs),
    /// Train the surrogate (DiT-Garment, rectified flow) on training tensors (`dataset
    /// tensors` output): checkpoints, resume, loss curves, EMA weights as safetensors.
    Train(TrainArgs),
    /// Pose a garment directly with a trained surrogate: every frame of a motion sampled from
    /// noise (Euler, rectified flow) with intersection guidance, recorded as MCAP like a
    /// simulation, so `render`, `view` and `compare` read it.
    Predict(PredictArgs),
    /// Score a model over a dataset's held-out splits with the paper's metrics, beside
    /// baselines that need no learning (lbs, lbs_nearest, floor, rest): JSON and a report
    /// with the paper's tables and pictures; resumable, per-sequence results cached.
    Evaluate(EvaluateArgs),
    /// Compare two `evaluate --json` results of the same recordings sequence by sequence: the
    /// mean difference, its standard error and the sequences each wins, per split, garment
    /// family, motion and garment (is B better than A beyond the sequences' own spread?).
    Paired(PairedArgs),
}

#[derive(Debug, Args)]
pub struct UvArgs {
    /// A garment (library design, built-in or template OBJ) or a garment recording (.mcap).
    pub source: String,
    /// Texels per side: 32, 64 or 128.
    #[arg(long, default_value_t = 64)]
    pub resolution: usize,
    /// Target: `displacement` (canonical cloth minus the rest template) or `lbs_residual`
    /// (canonical cloth minus the template skinned to the body).
    #[arg(long, default_value = "displacement", value_parser = ["displacement", "lbs_residual"])]
    pub target: String,
    /// Root rotation the canonical frame removes: `heading` or `full`.
    #[arg(long, default_value = "heading", value_parser = ["heading", "full"])]
    pub root: String,
    /// Score every K-th motion frame of a recording.
    #[arg(long, default_value_t = 5)]
    pub every: usize,
    /// Output folder: `position_map.png`, `mask.png`, `target_<k>.png`, `contact_sheet.png`.
    #[arg(long)]
    pub out: PathBuf,
    #[command(flatten)]
    pub model: ModelArgs,
    /// Write `resolution`, `coverage`, `texel_cm`, `vertices`, `uv_corners`, `charts` and, for
    /// a recording, `frames_scored`, `roundtrip_E_v_cm`, `roundtrip_p95_cm`,
    /// `roundtrip_max_cm`, `target_mean_cm`, `target` here.
    #[arg(long)]
    pub json: Option<PathBuf>,
}

#[derive(Debug, Args)]
pub struct DemoArgs {
    /// Output folder (created if missing).
    #[arg(long, required_unless_present = "print_config")]
    pub out: Option<PathBuf>,
    #[command(flatten)]
    pub scene: SceneArgs,
    /// Write an OBJ of every K-th frame (0 = none).
    #[arg(long, default_value_t = 15)]
    pub obj_every: usize,
    /// The surrogate that predicts the same sequence: `builtin` (the shipped ensemble of two
    /// networks), `builtin-single` (its first network alone), a run or ensemble folder, or `none`
    /// (simulate only). (`--model` is the body model, as in `simulate`.)
    #[arg(long, default_value = "builtin")]
    pub surrogate: String,
    /// Also write the numbers (frames, fps, timing, the prediction's scores) to this JSON file.
    #[arg(long)]
    pub json: Option<PathBuf>,
}

/// The garment-on-body sequence to simulate: a scene configuration (the defaults, a `--config`
/// file or the configuration a recording carries), then these flags over it.
#[derive(Debug, Args)]
pub struct SceneArgs {
    /// Scene configuration file (TOML, the keys `--print-config` prints); flags override its
    /// values.
    #[arg(long, conflicts_with = "config_from")]
    pub config: Option<PathBuf>,
    /// Print the resolved configuration as TOML and exit (nothing is simulated or written).
    #[arg(long)]
    pub print_config: bool,
    #[command(flatten)]
    pub inputs: SceneInputs,
    /// `--body-model`'s old name, still accepted where it means the body model.
    #[arg(long = "model", hide = true, conflicts_with = "body_model")]
    pub model_alias: Option<PathBuf>,
    /// Cloth-body friction coefficient. Default: 0.3.
    #[arg(long)]
    pub friction: Option<f64>,
    /// Substeps per 30 fps frame. Default: 4.
    #[arg(long)]
    pub substeps: Option<usize>,
    /// Maximum solver iterations per substep (with self-contact, up to 4x this in a step
    /// whose layers would otherwise cross). Default: 16.
    #[arg(long)]
    pub iterations: Option<usize>,
    /// Anderson acceleration: past iterations mixed into each iterate (0 turns it off, at
    /// most 8). Default: 0 (experimental: shallower on most sequences, unstable on some).
    #[arg(long)]
    pub acceleration: Option<usize>,
    /// Turns cloth-cloth contact off (it is on for garment scenes).
    #[arg(long)]
    pub no_self_contact: bool,
    /// Gap self-contact keeps between layers of the garment, m. Default: 0.004.
    #[arg(long)]
    pub self_contact_distance: Option<f64>,
    /// Coulomb friction coefficient between layers of the garment. Default: 0.3.
    #[arg(long)]
    pub self_friction: Option<f64>,
}

/// What a scene is made of (garment, motion, body, shape, material, frames): the flags
/// `simulate`, `demo` and `predict` share.
#[derive(Debug, Args)]
pub struct SceneInputs {
    /// Start from the configuration a recording carries in its metadata (to simulate or
    /// predict it again); flags override its values.
    #[arg(long)]
    pub config_from: Option<PathBuf>,
    /// Garment: a library design (see `garments list`; its template is made once and cached),
    /// the built-in skirt (`skirt`, `default`), or a template OBJ with UVs aligned to the
    /// default body in its canonical A-pose. Default: `default`.
    #[arg(long)]
    pub garment: Option<String>,
    /// Motion: a built-in name (with optional `:speed=..,amplitude=..,duration=..`), an
    /// AMASS .npz file or a BVH file (retargeted to SMPL), a file optionally followed by
    /// `:start=S,duration=D` (seconds) and, for BVH, `map=JOINTS.toml`. Default: `walk`.
    #[arg(long)]
    pub motion: Option<String>,
    /// SMPL-format .npz body model file (SMPL_NEUTRAL.npz ...); the licence-free default body
    /// if omitted (for `predict`, the body model the network was trained on).
    #[arg(long)]
    pub body_model: Option<PathBuf>,
    /// Shape coefficients, comma-separated (default: zeros).
    #[arg(long, value_delimiter = ',', allow_hyphen_values = true)]
    pub betas: Option<Vec<f64>>,
    /// Material as `k_s=N/m,rho=kg/m^2,k_b=N m` (any subset, over the configuration's; defaults
    /// 100, 0.2, 1e-5).
    #[arg(long)]
    pub material: Option<String>,
    /// Output frames, blend-in and settle included (default: the whole motion).
    #[arg(long)]
    pub frames: Option<usize>,
    /// Frames blending from the canonical pose and shape into the motion's first frame.
    /// Default: 30.
    #[arg(long)]
    pub blend_frames: Option<usize>,
    /// Frames holding the first frame after the blend. Default: 30.
    #[arg(long)]
    pub settle_frames: Option<usize>,
}

#[derive(Debug, Args)]
pub struct SimulateArgs {
    #[command(flatten)]
    pub scene: SceneArgs,
    /// Output recording (.mcap).
    #[arg(long, required_unless_present = "print_config")]
    pub out: Option<PathBuf>,
    /// Also record the body vertices of every frame (large; `record.body_vertices`).
    #[arg(long)]
    pub body_vertices: bool,
    /// Also record a `foxglove.SceneUpdate` channel (`/foxglove/scene`: garment and body
    /// triangle lists, z up) so the sequence plays in Foxglove's 3D panel (large;
    /// `record.foxglove`).
    #[arg(long)]
    pub foxglove: bool,
    /// Write every frame's garment (and body) as OBJ into this folder.
    #[arg(long)]
    pub obj_dir: Option<PathBuf>,
    /// With --obj-dir, write every K-th frame.
    #[arg(long, default_value_t = 1)]
    pub obj_every: usize,
    /// Write the run's statistics (`frames`, `finite`, `wall_s`, `frames_per_s`,
    /// `max_penetration_m`, `max_verts_inside`, `max_edge_stretch`, `vertices`, ...) here.
    #[arg(long)]
    pub json: Option<PathBuf>,
    /// Hide the progress bar.
    #[arg(long)]
    pub quiet: bool,
}

#[derive(Debug, Args)]
pub struct DrapeBenchArgs {
    /// Vertices per side of the cloth grid.
    #[arg(long, default_value_t = 64)]
    pub n: usize,
    /// Substeps per 30 fps frame.
    #[arg(long, default_value_t = 8)]
    pub substeps: usize,
    /// Iterations per substep.
    #[arg(long, default_value_t = 5)]
    pub iterations: usize,
    /// Turns cloth-cloth contact on (off by default: the benchmark scene has none).
    #[arg(long)]
    pub self_contact: bool,
    /// Folder for the final vertices (`final_n<N>.npy`, z-up, grid order i*n+j, as the other simulators' runs write them)
    /// and the result JSON.
    #[arg(long, default_value = "out/drape-bench")]
    pub out: PathBuf,
    /// Also write the result (the benchmark's keys: `n`, `t_sim_2s_wall_s`, `verts_inside_sphere`,
    /// `max_edge_stretch`, `p99_edge_stretch`, `drape_proxy`, `lowest_z_m`, `finite`) here.
    #[arg(long)]
    pub json: Option<PathBuf>,
}

#[derive(Debug, Args)]
pub struct RegressArgs {
    /// Higher resolutions and longer runs.
    #[arg(long)]
    pub long: bool,
    /// Only scenarios whose name contains this.
    #[arg(long, default_value = "")]
    pub only: String,
    /// Regenerate the golden sequences (regress/goldens/) instead of checking them; needs
    /// --reason, which is recorded in regress/goldens/BLESSED.md.
    #[arg(long, requires = "reason")]
    pub bless: bool,
    /// Why the goldens are regenerated.
    #[arg(long)]
    pub reason: Option<String>,
    /// Write `{"scenarios": [{"name", "expected", "measured", "tolerance", "pass", "unit"}]}`.
    #[arg(long)]
    pub json: Option<PathBuf>,
}

#[derive(Debug, Args)]
pub struct CompareArgs {
    /// Ground truth: a recording, or a folder of a capture's frames (`.obj`, `.ply` or `.pkl`
    /// meshes of any topology, frame k the k-th file by name; 4D-Dress's pickles are read
    /// without running them), scored by the correspondence-free metrics alone.
    pub a: PathBuf,
    /// Recording to score (the same garment template as a recording A).
    pub b: PathBuf,
    /// Body model the recordings were made with (default body if omitted); used to rebuild the
    /// body for E_c when the recordings do not carry body vertices.
    #[command(flatten)]
    pub model: ModelArgs,
    /// Print every scored frame.
    #[arg(long)]
    pub per_frame: bool,
    /// Write `E_v`, `E_CD`, `E_CD_cm`, `E_n`, `E_c`, `E_c_vertex`, `E_b`, `E_s`, `E_d`,
    /// `frames_scored` (and units, per-frame scores) here; against a capture, `E_CD`,
    /// `E_CD_cm`, `E_n`, `E_c`, `E_c_vertex`, `distance_p90_cm` and `not_applicable`.
    #[arg(long)]
    pub json: Option<PathBuf>,
    /// Seed of the surface samples.
    #[arg(long, default_value_t = 0)]
    pub seed: u64,
    /// In a capture of pickled frames that hold one mesh per garment label (4D-Dress's
    /// `Semantic/clothes/cloth-f*.pkl`: `upper`, `lower`, `outer`, ...), the one to score
    /// against.
    #[arg(long)]
    pub capture_garment: Option<String>,
}

#[derive(Debug, Args)]
pub struct SynthArgs {
    /// Dataset spec (TOML; `--example-spec tiny` prints a commented one).
    #[arg(long, required_unless_present = "example_spec")]
    pub spec: Option<PathBuf>,
    /// Dataset folder (created; a re-run resumes it).
    #[arg(long, required_unless_present = "example_spec")]
    pub out: Option<PathBuf>,
    /// Print an example spec and exit: `tiny` (4 short sequences, the default) or `paper`
    /// (paper-like).
    #[arg(long, value_parser = ["tiny", "paper"], num_args = 0..=1, default_missing_value = "tiny")]
    pub example_spec: Option<String>,
    /// Sequences simulated at once (default: the number of cores).
    #[arg(long)]
    pub jobs: Option<usize>,
    /// This task's shard as K/N (K from 0). Default: from a Slurm job array
    /// (SLURM_ARRAY_TASK_ID, _COUNT, _MIN) or a Kubernetes indexed job (JOB_COMPLETION_INDEX
    /// with --shard-count), else the whole dataset.
    #[arg(long)]
    pub shard: Option<String>,
    /// Number of shards of a Kubernetes indexed job (its `completions`).
    #[arg(long)]
    pub shard_count: Option<usize>,
    #[command(flatten)]
    pub model: ModelArgs,
    /// Hide the progress bar.
    #[arg(long)]
    pub quiet: bool,
    /// Write the run's numbers (`planned`, `simulated`, `skipped`, `failed`, `frames`,
    /// `frames_per_s`, `sequences_per_hour`, ...) here.
    #[arg(long)]
    pub json: Option<PathBuf>,
}

#[derive(Debug, Subcommand)]
pub enum DatasetCommand {
    /// Check a dataset: checksums, recordings, counts against the plan, gate results; exits
    /// non-zero on any mismatch.
    Verify {
        /// Dataset folder.
        dir: PathBuf,
        /// Also write `sequences`, `planned`, `passed`, `problems`, `ok` here.
        #[arg(long)]
        json: Option<PathBuf>,
    },
    /// Counts per split, garment and motion; material histograms; gate failures; frames and
    /// hours.
    Stats {
        /// Dataset folder.
        dir: PathBuf,
        /// Also write `sequences`, `failed`, `frames`, `splits`, ... here.
        #[arg(long)]
        json: Option<PathBuf>,
    },
    /// Turn a synthesized dataset (its sequences that passed their gates) into the
    /// surrogate's training tensors: safetensors shards per split, the templates' position
    /// maps and masks, and `manifest.json` (layout, train-split normalization, checksums).
    Tensors {
        /// Dataset folders (`synth` output with its manifest): one, or several whose specs give
        /// the same material ranges (say a procedural dataset and a motion-capture one),
        /// combined into one tensor set split by split.
        #[arg(required = true, num_args = 1..)]
        dirs: Vec<PathBuf>,
        /// Output folder.
        #[arg(long)]
        out: PathBuf,
        /// Texels per side: 32, 64 or 128.
        #[arg(long, default_value_t = 64)]
        resolution: usize,
        /// `lbs_residual` (canonical cloth minus the template skinned to the body; its tensors
        /// also hold the body inputs) or `displacement` (minus the rest template, the paper's).
        #[arg(long, default_value = "lbs_residual", value_parser = ["displacement", "lbs_residual"])]
        target: String,
        /// Condition scaling: `bounded` (6D rotations unscaled, a pose-velocity block, a std
        /// floor for the rest), `history` (`bounded` and the body's exponentially weighted past
        /// at 0.1, 0.3 and 1 s) or `zscore` (every value z-scored, no velocities: the layout
        /// before 2026-12-03).
        #[arg(long, default_value = "bounded", value_parser = ["bounded", "history", "zscore"])]
        conditions: String,
        /// Also store, per texel, the offset from the skinned template to the nearest point
        /// of the posed body and that point's normal (6 more body channels, `lbs_residual`
        /// only), for models with `body_nearest = true`.
        #[arg(long)]
        body_nearest: bool,
        /// Earlier frames in each pose window.
        #[arg(long, default_value_t = 2)]
        window: usize,
        /// Every K-th motion frame of a sequence becomes a sample.
        #[arg(long, default_value_t = 1)]
        every: usize,
        /// Frames per shard file.
        #[arg(long, default_value_t = 2048)]
        shard_frames: usize,
        /// Held-out splits whose sequences join the train split, comma-separated (say
        /// `test_grid` of a validation set, to refit a chosen recipe on training and
        /// validation data together); the manifest's `joined_to_train` lists them.
        #[arg(long, value_delimiter = ',')]
        train_splits: Vec<String>,
        /// Also hold every training sequence's mirror image (left and right swapped: the
        /// motion mirrored joint by joint, the cloth carried by the template's mirror
        /// correspondence), for templates symmetric within `--mirror-max-gap-cm`; the manifest
        /// gives each template's `mirror_gap_m` and the train split's `mirrored` count.
        #[arg(long)]
        mirror: bool,
        /// With `--mirror`: the largest mean distance (cm) from a template's mirrored vertices
        /// to its surface at which it is mirrored.
        #[arg(long, default_value_t = 0.5)]
        mirror_max_gap_cm: f64,
        #[command(flatten)]
        model: ModelArgs,
        /// Hide the progress bar.
        #[arg(long)]
        quiet: bool,
    },
    /// The ground truth's own spread: each finished sequence simulated again from its
    /// recording's configuration with one setting nudged, and scored against the recording
    /// as `evaluate` scores a prediction (per split, garment family and motion).
    Spread {
        /// Dataset folder.
        dir: PathBuf,
        /// Splits to rerun, comma-separated (default: all).
        #[arg(long, value_delimiter = ',')]
        splits: Vec<String>,
        /// What changes: `k_s` (1% stiffer), `substeps` (one more), `iterations` (one more
        /// per substep) or `none` (the engine is deterministic: zero but for f32 rounding).
        #[arg(long, default_value = "k_s")]
        perturb: String,
        /// At most this many sequences (the first in the manifest).
        #[arg(long)]
        max_sequences: Option<usize>,
        /// Write `splits`, `families`, `motions` (rows of the `resimulated` method, keys as
        /// `evaluate`'s) and `sequences` here.
        #[arg(long)]
        json: Option<PathBuf>,
        /// Hide the progress bar.
        #[arg(long)]
        quiet: bool,
    },
    /// Merge shard folders (or one shared folder) into OUT and write its manifest; refuses
    /// while any planned sequence is unfinished.
    Merge {
        /// Output folder (may be one of the inputs).
        out: PathBuf,
        /// Shard folders.
        #[arg(required = true)]
        dirs: Vec<PathBuf>,
    },
}

/// What the garment is coloured by in `render`.
#[derive(Debug, Clone, Copy, PartialEq, Eq, clap::ValueEnum)]
pub enum ColourBy {
    /// Largest stretch of the vertex's edges against the template (length / rest length).
    Stretch,
    /// Depth inside the body, mm.
    Penetration,
    /// Distance to the same vertex in the `--against` recording, cm.
    Error,
}

impl From<ColourBy> for render::recording::ColourBy {
    fn from(by: ColourBy) -> Self {
        match by {
            ColourBy::Stretch => Self::Stretch,
            ColourBy::Penetration => Self::Penetration,
            ColourBy::Error => Self::Error,
        }
    }
}

#[derive(Debug, Args)]
pub struct RenderArgs {
    /// Recording to draw (.mcap from `simulate` or `demo`).
    pub recording: PathBuf,
    /// Frames to draw, comma-separated (default: six evenly spaced frames).
    #[arg(long, value_delimiter = ',')]
    pub frames: Vec<usize>,
    /// Output folder for `frame_<k>_<view>.png`, `contact_sheet.png` and `sequence.gif`.
    #[arg(long)]
    pub out: PathBuf,
    /// Cameras, comma-separated: front, side, three-quarter.
    #[arg(long, value_delimiter = ',', default_value = "three-quarter")]
    pub views: Vec<String>,
    /// Picture width and height, pixels.
    #[arg(long, default_value_t = 512)]
    pub size: u32,
    /// Anti-aliasing: samples per pixel along each axis (1 = off).
    #[arg(long, default_value_t = 2)]
    pub ssaa: u32,
    /// Colour the garment by a per-vertex quantity, with a colour bar.
    #[arg(long, alias = "colour-by", value_enum)]
    pub color_by: Option<ColourBy>,
    /// Reference recording for `--color-by error` (same garment template).
    #[arg(long)]
    pub against: Option<PathBuf>,
    /// Colour bar range as `min,max` (defaults: stretch 0.9,1.2; penetration 0,10 mm; error
    /// 0,5 cm).
    #[arg(long, value_delimiter = ',', allow_hyphen_values = true)]
    pub range: Vec<f32>,
    /// Leave the body out.
    #[arg(long)]
    pub no_body: bool,
    /// Also write `sequence.gif`: the whole sequence from the first view.
    #[arg(long)]
    pub gif: bool,
    /// GIF: every K-th frame.
    #[arg(long, default_value_t = 2)]
    pub gif_every: usize,
    /// GIF picture size, pixels.
    #[arg(long, default_value_t = 320)]
    pub gif_size: u32,
    #[command(flatten)]
    pub model: ModelArgs,
    /// Write `images` (PNG paths, frames first), `pixels_garment` (garment pixels in the first
    /// image), `sheet`, `gif` and timings here.
    #[arg(long)]
    pub json: Option<PathBuf>,
}

#[derive(Debug, Args)]
pub struct ViewArgs {
    /// One or two recordings (two play side by side, synchronized).
    #[arg(required = true, num_args = 1..=2)]
    pub recordings: Vec<PathBuf>,
    /// Output HTML file.
    #[arg(long)]
    pub out: PathBuf,
    /// Leave the body out (smaller file).
    #[arg(long)]
    pub no_body: bool,
    /// Keep every K-th frame (smaller file for long sequences).
    #[arg(long, default_value_t = 1)]
    pub every: usize,
    #[command(flatten)]
    pub model: ModelArgs,
}

/// Where the body comes from and its shape.
#[derive(Debug, Args)]
pub struct ModelArgs {
    /// SMPL-format .npz body model file (SMPL_NEUTRAL.npz ...); the licence-free default body
    /// if omitted. Named as in `predict` and `evaluate`, where `--model` is the trained network
    /// (`--model` is still accepted here, unlisted).
    #[arg(long = "body-model", alias = "model")]
    pub body_model: Option<PathBuf>,
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
    /// Take the pose and translation from this motion (built-in name, AMASS .npz or BVH) ...
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
        /// Built-in name (optionally `name:speed=..,amplitude=..,duration=..`), AMASS .npz or
        /// BVH file (optionally `FILE:start=S,duration=D`, and `map=JOINTS.toml` for BVH).
        motion: String,
        #[command(flatten)]
        model: ModelArgs,
        /// Also write the numbers to this JSON file.
        #[arg(long)]
        json: Option<PathBuf>,
    },
    /// Export a motion as an MCAP sequence with body poses, joints and vertices per frame, or
    /// (`--out FILE.npz`) as an AMASS-style .npz of its poses at 30 fps.
    Export {
        /// Built-in name (optionally with parameters), AMASS .npz or BVH file.
        motion: String,
        /// Output: .mcap (body sequence) or .npz (AMASS-style: `poses` N x 156, `trans`,
        /// `betas`, `gender`, `mocap_framerate`; z up as AMASS; no blend-in).
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
