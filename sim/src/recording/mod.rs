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

use crate::config::{RecordConfig, SceneConfig};
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
    /// What the resolved scene configuration the sequence was simulated from adds to the
    /// fields above (absent in recordings made before configurations existed, and in
    /// predicted sequences that no configuration reproduces); [`SequenceMeta::scene_config`]
    /// puts the whole configuration together, and `simulate --config-from` runs it again.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub config: Option<RecordedScene>,
}

/// The keys of a scene configuration that [`SequenceMeta`] does not already hold: each value
/// is stored once per recording. Recordings made before this split carry the whole
/// configuration here; its other keys equal the metadata's and are not read.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct RecordedScene {
    /// The garment as configured (a library name, built-in or file).
    pub garment: String,
    /// The motion as configured.
    pub motion: String,
    /// The shape as configured (the metadata's `betas` are completed to the body model's
    /// count).
    pub betas: Vec<f64>,
    /// The body model file, when one was given.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub model: Option<String>,
    /// Frames as configured (the whole motion when absent).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub frames: Option<usize>,
    /// What the recording carries besides the garment.
    pub record: RecordConfig,
}

impl RecordedScene {
    /// What `config` adds to the metadata of its sequence.
    pub fn of(config: &SceneConfig) -> Self {
        Self {
            garment: config.garment.clone(),
            motion: config.motion.clone(),
            betas: config.betas.clone(),
            model: config.model.clone(),
            frames: config.frames,
            record: config.record,
        }
    }
}

impl SequenceMeta {
    /// The whole scene configuration the sequence was simulated from, or `None` for a
    /// recording without one.
    pub fn scene_config(&self) -> Option<SceneConfig> {
        let scene = self.config.as_ref()?;
        Some(SceneConfig {
            garment: scene.garment.clone(),
            motion: scene.motion.clone(),
            model: scene.model.clone(),
            betas: scene.betas.clone(),
            friction: self.friction,
            frames: scene.frames,
            blend_frames: self.blend_frames,
            settle_frames: self.settle_frames,
            seed: self.seed,
            material: self.material,
            solver: self.solver,
            record: scene.record,
        })
    }
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

#[cfg(test)]
mod tests {
    use super::*;

    /// A configuration unlike the default in every key the metadata holds.
    fn config() -> SceneConfig {
        let mut c = SceneConfig {
            garment: "skirt".into(),
            motion: "walk:speed=1.2".into(),
            betas: vec![0.5, -0.25],
            friction: 0.45,
            frames: Some(40),
            blend_frames: 7,
            settle_frames: 3,
            seed: Some(99),
            ..SceneConfig::default()
        };
        c.material.stretch = 80.0;
        c.solver.substeps = 2;
        c.record.body_vertices = true;
        c
    }

    fn meta(c: &SceneConfig, recorded: Option<serde_json::Value>) -> serde_json::Value {
        let meta = SequenceMeta {
            software: "test".into(),
            garment: c.garment.clone(),
            motion: c.motion.clone(),
            body_model: "smpl".into(),
            betas: [c.betas.as_slice(), &[0.0; 8]].concat(),
            fps: 30.0,
            frames: 40,
            blend_frames: c.blend_frames,
            settle_frames: c.settle_frames,
            material: c.material,
            friction: c.friction,
            seed: c.seed,
            solver: c.solver,
            units: UNITS.into(),
            config: Some(RecordedScene::of(c)),
        };
        let mut json = serde_json::to_value(meta).unwrap();
        if let Some(value) = recorded {
            json["config"] = value;
        }
        json
    }

    #[test]
    fn each_scene_value_is_stored_once_and_the_whole_configuration_comes_back() {
        let c = config();
        let json = meta(&c, None);
        let recorded = json["config"].as_object().unwrap();
        for key in ["material", "solver", "friction", "seed", "blend_frames"] {
            assert!(
                json.get(key).is_some() && !recorded.contains_key(key),
                "{key}"
            );
        }
        let read: SequenceMeta = serde_json::from_value(json).unwrap();
        assert_eq!(read.scene_config(), Some(c));
    }

    #[test]
    fn a_recording_with_the_whole_configuration_reads_as_before() {
        let c = config();
        let json = meta(&c, Some(serde_json::to_value(&c).unwrap()));
        let read: SequenceMeta = serde_json::from_value(json).unwrap();
        assert_eq!(read.scene_config(), Some(c));
    }
}
