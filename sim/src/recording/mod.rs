//! Sequence recordings: one MCAP file per sequence (channels and schemas in docs/FORMATS.md),
//! one writer for garment and body sequences ([`SequenceWriter`], fed plain arrays, so the
//! engine and the surrogate write the same files) and the reader the rest of the project uses
//! ([`Recording`]). Raw arrays are little-endian with `dtype` and `shape` in the channel
//! metadata, so the Python `mcap` package and Foxglove read them without our code.

mod body_sequence;
mod foxglove;
mod mcap_read;
mod reader;
mod stats;
mod writer;

pub use body_sequence::write_body_sequence;
pub use reader::{RecordedBody, Recording};
pub use stats::FrameStats;
pub use writer::{Channels, FrameRecord, SequenceWriter};

use serde::{Deserialize, Serialize};

use crate::config::SceneConfig;
use crate::params::{Material, SolverParams};

/// Topic of the sequence metadata (JSON, once at time 0).
pub const META_TOPIC: &str = "/sequence/meta";
/// Template positions (float32 [V, 3], once).
pub const TEMPLATE_POSITIONS_TOPIC: &str = "/garment/template/positions";
/// Template triangles (uint32 [F, 3], once).
pub const TEMPLATE_TRIANGLES_TOPIC: &str = "/garment/template/triangles";
/// Template UVs (float32 [U, 2], once).
pub const TEMPLATE_UVS_TOPIC: &str = "/garment/template/uvs";
/// Template UV triangles (uint32 [F, 3], once).
pub const TEMPLATE_UV_TRIANGLES_TOPIC: &str = "/garment/template/uv_triangles";
/// Garment vertices per frame (float32 [V, 3]).
pub const GARMENT_TOPIC: &str = "/garment/vertices";
/// Body pose per frame (JSON).
pub const POSE_TOPIC: &str = "/body/pose";
/// Body vertices per frame (float32 [B, 3], optional).
pub const BODY_VERTICES_TOPIC: &str = "/body/vertices";
/// Body joints per frame (float32 [24, 3], optional).
pub const BODY_JOINTS_TOPIC: &str = "/body/joints";
/// Body triangles (uint32 [T, 3], once, with the body vertices).
pub const BODY_FACES_TOPIC: &str = "/body/faces";
/// Solver statistics per frame (JSON).
pub const STATS_TOPIC: &str = "/sim/stats";
/// Optional 3D scene for Foxglove's 3D panel (`foxglove.SceneUpdate`, JSON), z up.
pub const FOXGLOVE_SCENE_TOPIC: &str = "/foxglove/scene";

/// Units and axes of every recording.
pub const UNITS: &str = "metres, seconds, radians, kg; y up, body facing +z";

/// What a garment sequence is: everything needed to reproduce it or learn from it.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct SequenceMeta {
    /// Producing software and version.
    pub software: String,
    /// Garment name.
    pub garment: String,
    /// Motion id (built-in name with parameters, or file).
    pub motion: String,
    /// Body model name.
    pub body_model: String,
    /// Body shape.
    pub betas: Vec<f64>,
    /// Frames per second.
    pub fps: f64,
    /// Frames recorded (frame 0 = template on the canonical body).
    pub frames: usize,
    /// Blend-in frames at the start.
    pub blend_frames: usize,
    /// Settle frames after the blend-in.
    pub settle_frames: usize,
    /// Material.
    pub material: Material,
    /// Cloth-body friction coefficient.
    pub friction: f64,
    /// Random seed the sequence was sampled with, if any.
    pub seed: Option<u64>,
    /// Solver settings.
    pub solver: SolverParams,
    /// Units and axes.
    pub units: String,
    /// The resolved scene configuration the sequence was simulated from (absent in
    /// recordings made before configurations existed, and in predicted sequences that no
    /// configuration reproduces); `simulate --config-from` runs it again.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub config: Option<SceneConfig>,
}

/// What a body-only sequence (`motions export`) is.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct BodySequenceMeta {
    /// Producing software and version.
    pub software: String,
    /// Motion id (built-in name with parameters, or file).
    pub motion: String,
    /// Body model name.
    pub body_model: String,
    /// Body shape.
    pub betas: Vec<f64>,
    /// Frames per second.
    pub fps: f64,
    /// Frames recorded.
    pub frames: usize,
    /// Blend-in frames at the start.
    pub blend_frames: usize,
    /// Settle frames after the blend-in.
    pub settle_frames: usize,
    /// Units and axes.
    pub units: String,
}

/// The template arrays.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct TemplateArrays {
    /// Rest positions, m.
    pub positions: Vec<[f64; 3]>,
    /// Triangles.
    pub triangles: Vec<[u32; 3]>,
    /// UVs.
    pub uvs: Vec<[f64; 2]>,
    /// UV triangles.
    pub uv_triangles: Vec<[u32; 3]>,
}

impl From<&garments::Garment> for TemplateArrays {
    /// The arrays a recording stores of a garment template (its rest mesh and UV layout).
    fn from(g: &garments::Garment) -> Self {
        Self {
            positions: g.positions.clone(),
            triangles: g.triangles.clone(),
            uvs: g.uvs.clone(),
            uv_triangles: g.uv_triangles.clone(),
        }
    }
}

/// Body pose message of one frame.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct PoseRecord {
    /// Frame index.
    pub frame: usize,
    /// Seconds since frame 0.
    pub time_s: f64,
    /// SMPL axis-angle pose (72), radians.
    pub pose: Vec<f64>,
    /// Root translation (3), m.
    pub transl: [f64; 3],
    /// Body shape of this frame (ramped during the blend-in).
    #[serde(default)]
    pub betas: Vec<f64>,
}
