//! Sequence recordings: one MCAP file per sequence (channels and schemas in docs/FORMATS.md),
//! and the reader the rest of the project uses. Raw arrays are little-endian with `dtype` and
//! `shape` in the channel metadata, so the Python `mcap` package reads them without our code.

use std::collections::BTreeMap;
use std::io::{Seek, Write};
use std::path::Path;

use mcap::records::{MessageHeader, Metadata};
use mcap::{Compression, WriteOptions};
use serde::{Deserialize, Serialize};

use crate::cloth::Vec3;
use crate::error::{Error, Result};
use crate::params::{Material, SolverParams};
use crate::scene::{FrameOutput, FrameStats};

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
/// Body triangles (uint32 [T, 3], once, with the body vertices).
pub const BODY_FACES_TOPIC: &str = "/body/faces";
/// Solver statistics per frame (JSON).
pub const STATS_TOPIC: &str = "/sim/stats";
/// Optional 3D scene for Foxglove's 3D panel (`foxglove.SceneUpdate`, JSON), z up.
pub const FOXGLOVE_SCENE_TOPIC: &str = "/foxglove/scene";

/// Material with its units spelled out in the keys.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct MaterialRecord {
    /// Stretch stiffness k_s, N/m.
    pub k_s_n_per_m: f64,
    /// Area density rho, kg/m^2.
    pub rho_kg_per_m2: f64,
    /// Bending stiffness k_b, N m.
    pub k_b_n_m: f64,
}

impl From<Material> for MaterialRecord {
    fn from(m: Material) -> Self {
        Self {
            k_s_n_per_m: m.stretch,
            rho_kg_per_m2: m.density,
            k_b_n_m: m.bending,
        }
    }
}

/// What a sequence is: everything needed to reproduce it or learn from it.
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
    pub material: MaterialRecord,
    /// Cloth-body friction coefficient.
    pub friction: f64,
    /// Random seed the sequence was sampled with, if any.
    pub seed: Option<u64>,
    /// Solver settings.
    pub solver: SolverParams,
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
    pub betas: Vec<f64>,
}

const META_SCHEMA: &str = r#"{"title": "dit_garment.SequenceMeta", "type": "object", "description": "see docs/FORMATS.md"}"#;
const POSE_SCHEMA: &str = r#"{"title": "dit_garment.GarmentBodyPose", "type": "object", "properties": {"frame": {"type": "integer"}, "time_s": {"type": "number"}, "pose": {"type": "array", "minItems": 72, "maxItems": 72}, "transl": {"type": "array", "minItems": 3, "maxItems": 3}, "betas": {"type": "array"}}}"#;
/// Foxglove's `foxglove.SceneUpdate` message, the parts this project writes (triangle lists);
/// Foxglove recognizes the schema by its name.
const FOXGLOVE_SCENE_SCHEMA: &str = r#"{
  "title": "foxglove.SceneUpdate",
  "description": "An update to the entities displayed in a 3D scene",
  "type": "object",
  "properties": {
    "deletions": {"type": "array", "items": {"type": "object"}},
    "entities": {"type": "array", "items": {"type": "object", "properties": {
      "timestamp": {"type": "object", "properties": {"sec": {"type": "integer"}, "nsec": {"type": "integer"}}},
      "frame_id": {"type": "string"},
      "id": {"type": "string"},
      "lifetime": {"type": "object", "properties": {"sec": {"type": "integer"}, "nsec": {"type": "integer"}}},
      "frame_locked": {"type": "boolean"},
      "metadata": {"type": "array"},
      "arrows": {"type": "array"}, "cubes": {"type": "array"}, "spheres": {"type": "array"},
      "cylinders": {"type": "array"}, "lines": {"type": "array"}, "texts": {"type": "array"},
      "models": {"type": "array"},
      "triangles": {"type": "array", "items": {"type": "object", "properties": {
        "pose": {"type": "object"},
        "points": {"type": "array", "items": {"type": "object", "properties": {"x": {"type": "number"}, "y": {"type": "number"}, "z": {"type": "number"}}}},
        "color": {"type": "object", "properties": {"r": {"type": "number"}, "g": {"type": "number"}, "b": {"type": "number"}, "a": {"type": "number"}}},
        "colors": {"type": "array"},
        "indices": {"type": "array", "items": {"type": "integer", "minimum": 0}}
      }}}
    }}}
  }
}"#;
const STATS_SCHEMA: &str = r#"{"title": "dit_garment.FrameStats", "type": "object", "description": "see docs/FORMATS.md"}"#;

fn raw(dtype: &str, shape: String) -> BTreeMap<String, String> {
    BTreeMap::from([
        ("dtype".to_string(), dtype.to_string()),
        ("shape".to_string(), shape),
        ("byte_order".to_string(), "little".to_string()),
    ])
}

fn f32_bytes(values: impl Iterator<Item = f64>) -> Vec<u8> {
    values.flat_map(|v| (v as f32).to_le_bytes()).collect()
}

fn u32_bytes(values: &[[u32; 3]]) -> Vec<u8> {
    values
        .iter()
        .flatten()
        .flat_map(|v| v.to_le_bytes())
        .collect()
}

fn mcap_error(e: impl std::fmt::Display) -> Error {
    Error::Recording {
        path: String::new(),
        message: e.to_string(),
    }
}

/// Streams a sequence into an MCAP file.
pub struct RecordingWriter<W: Write + Seek> {
    writer: mcap::Writer<W>,
    garment: u16,
    pose: u16,
    stats: u16,
    body: Option<u16>,
    foxglove: Option<FoxgloveScene>,
}

/// The Foxglove scene channel and the triangles its messages repeat.
struct FoxgloveScene {
    channel: u16,
    garment_triangles: Vec<[u32; 3]>,
    body_faces: Vec<[u32; 3]>,
}

/// One `foxglove.TriangleListPrimitive` entity: y-up points turned z-up by the pose (+90
/// degrees about x), rounded to 0.1 mm to keep the JSON short.
fn foxglove_entity(
    id: &str,
    time_ns: u64,
    points: impl Iterator<Item = [f64; 3]>,
    triangles: &[[u32; 3]],
    rgb: [f64; 3],
) -> serde_json::Value {
    let round = |v: f64| (v * 1e4).round() / 1e4;
    let points: Vec<serde_json::Value> = points
        .map(|p| serde_json::json!({"x": round(p[0]), "y": round(p[1]), "z": round(p[2])}))
        .collect();
    let half = std::f64::consts::FRAC_1_SQRT_2;
    serde_json::json!({
        "timestamp": {"sec": time_ns / 1_000_000_000, "nsec": time_ns % 1_000_000_000},
        "frame_id": "world", "id": id,
        "lifetime": {"sec": 0, "nsec": 0}, "frame_locked": false, "metadata": [],
        "arrows": [], "cubes": [], "spheres": [], "cylinders": [], "lines": [], "texts": [],
        "models": [],
        "triangles": [{
            "pose": {"position": {"x": 0.0, "y": 0.0, "z": 0.0},
                     "orientation": {"x": half, "y": 0.0, "z": 0.0, "w": half}},
            "points": points,
            "color": {"r": rgb[0], "g": rgb[1], "b": rgb[2], "a": 1.0},
            "colors": [],
            "indices": triangles.iter().flatten().collect::<Vec<_>>(),
        }],
    })
}

impl<W: Write + Seek> RecordingWriter<W> {
    /// Starts a recording: metadata and the template; body vertices are written per frame if
    /// `body_faces` is given.
    pub fn new(
        out: W,
        meta: &SequenceMeta,
        template: &TemplateArrays,
        body_faces: Option<&[[u32; 3]]>,
    ) -> Result<Self> {
        let mut writer = WriteOptions::new()
            .compression(Some(Compression::Zstd))
            .chunk_size(Some(4 << 20))
            .profile("")
            .create(out)
            .map_err(mcap_error)?;
        let meta_schema = writer
            .add_schema(
                "dit_garment.SequenceMeta",
                "jsonschema",
                META_SCHEMA.as_bytes(),
            )
            .map_err(mcap_error)?;
        let pose_schema = writer
            .add_schema(
                "dit_garment.GarmentBodyPose",
                "jsonschema",
                POSE_SCHEMA.as_bytes(),
            )
            .map_err(mcap_error)?;
        let stats_schema = writer
            .add_schema(
                "dit_garment.FrameStats",
                "jsonschema",
                STATS_SCHEMA.as_bytes(),
            )
            .map_err(mcap_error)?;
        let none = BTreeMap::new();
        let meta_channel = writer
            .add_channel(meta_schema, META_TOPIC, "json", &none)
            .map_err(mcap_error)?;
        let (v, f, u) = (
            template.positions.len(),
            template.triangles.len(),
            template.uvs.len(),
        );
        let octet = "application/octet-stream";
        let tp = writer
            .add_channel(
                0,
                TEMPLATE_POSITIONS_TOPIC,
                octet,
                &raw("float32", format!("[{v}, 3]")),
            )
            .map_err(mcap_error)?;
        let tt = writer
            .add_channel(
                0,
                TEMPLATE_TRIANGLES_TOPIC,
                octet,
                &raw("uint32", format!("[{f}, 3]")),
            )
            .map_err(mcap_error)?;
        let tu = writer
            .add_channel(
                0,
                TEMPLATE_UVS_TOPIC,
                octet,
                &raw("float32", format!("[{u}, 2]")),
            )
            .map_err(mcap_error)?;
        let tut = writer
            .add_channel(
                0,
                TEMPLATE_UV_TRIANGLES_TOPIC,
                octet,
                &raw("uint32", format!("[{f}, 3]")),
            )
            .map_err(mcap_error)?;
        let garment = writer
            .add_channel(
                0,
                GARMENT_TOPIC,
                octet,
                &raw("float32", format!("[{v}, 3]")),
            )
            .map_err(mcap_error)?;
        let pose = writer
            .add_channel(pose_schema, POSE_TOPIC, "json", &none)
            .map_err(mcap_error)?;
        let stats = writer
            .add_channel(stats_schema, STATS_TOPIC, "json", &none)
            .map_err(mcap_error)?;
        let mut info: BTreeMap<String, String> = BTreeMap::new();
        if let serde_json::Value::Object(map) = serde_json::to_value(meta).map_err(mcap_error)? {
            for (k, value) in map {
                info.insert(
                    k,
                    match value {
                        serde_json::Value::String(s) => s,
                        other => other.to_string(),
                    },
                );
            }
        }
        writer
            .write_metadata(&Metadata {
                name: "sequence".to_string(),
                metadata: info,
            })
            .map_err(mcap_error)?;
        let once = |channel_id| MessageHeader {
            channel_id,
            sequence: 0,
            log_time: 0,
            publish_time: 0,
        };
        writer
            .write_to_known_channel(
                &once(meta_channel),
                &serde_json::to_vec(meta).map_err(mcap_error)?,
            )
            .map_err(mcap_error)?;
        writer
            .write_to_known_channel(
                &once(tp),
                &f32_bytes(template.positions.iter().flatten().copied()),
            )
            .map_err(mcap_error)?;
        writer
            .write_to_known_channel(&once(tt), &u32_bytes(&template.triangles))
            .map_err(mcap_error)?;
        writer
            .write_to_known_channel(
                &once(tu),
                &f32_bytes(template.uvs.iter().flatten().copied()),
            )
            .map_err(mcap_error)?;
        writer
            .write_to_known_channel(&once(tut), &u32_bytes(&template.uv_triangles))
            .map_err(mcap_error)?;
        let body = match body_faces {
            Some(faces) => {
                let nv = faces
                    .iter()
                    .flatten()
                    .copied()
                    .max()
                    .map_or(0, |m| m as usize + 1);
                let bv = writer
                    .add_channel(
                        0,
                        BODY_VERTICES_TOPIC,
                        octet,
                        &raw("float32", format!("[{nv}, 3]")),
                    )
                    .map_err(mcap_error)?;
                let bf = writer
                    .add_channel(
                        0,
                        BODY_FACES_TOPIC,
                        octet,
                        &raw("uint32", format!("[{}, 3]", faces.len())),
                    )
                    .map_err(mcap_error)?;
                writer
                    .write_to_known_channel(&once(bf), &u32_bytes(faces))
                    .map_err(mcap_error)?;
                Some(bv)
            }
            None => None,
        };
        Ok(Self {
            writer,
            garment,
            pose,
            stats,
            body,
            foxglove: None,
        })
    }

    /// Adds a `foxglove.SceneUpdate` channel (garment and, with `body_faces`, body as triangle
    /// lists every frame) so Foxglove's 3D panel plays the sequence. Large: every frame repeats
    /// the triangles.
    pub fn with_foxglove_scene(
        mut self,
        garment_triangles: &[[u32; 3]],
        body_faces: Option<&[[u32; 3]]>,
    ) -> Result<Self> {
        let schema = self
            .writer
            .add_schema(
                "foxglove.SceneUpdate",
                "jsonschema",
                FOXGLOVE_SCENE_SCHEMA.as_bytes(),
            )
            .map_err(mcap_error)?;
        let channel = self
            .writer
            .add_channel(schema, FOXGLOVE_SCENE_TOPIC, "json", &BTreeMap::new())
            .map_err(mcap_error)?;
        self.foxglove = Some(FoxgloveScene {
            channel,
            garment_triangles: garment_triangles.to_vec(),
            body_faces: body_faces.map(<[_]>::to_vec).unwrap_or_default(),
        });
        Ok(self)
    }

    /// Appends one frame.
    pub fn write_frame(&mut self, frame: &FrameOutput, fps: f64) -> Result<()> {
        let k = frame.index;
        let time_ns = (k as f64 / fps * 1e9).round() as u64;
        let header = |channel_id| MessageHeader {
            channel_id,
            sequence: k as u32,
            log_time: time_ns,
            publish_time: time_ns,
        };
        let garment = f32_bytes(frame.garment.iter().flat_map(|p: &Vec3| [p.x, p.y, p.z]));
        self.writer
            .write_to_known_channel(&header(self.garment), &garment)
            .map_err(mcap_error)?;
        let pose = PoseRecord {
            frame: k,
            time_s: k as f64 / fps,
            pose: frame.pose.pose.to_vec(),
            transl: frame.pose.transl,
            betas: frame.betas.to_vec(),
        };
        self.writer
            .write_to_known_channel(
                &header(self.pose),
                &serde_json::to_vec(&pose).map_err(mcap_error)?,
            )
            .map_err(mcap_error)?;
        self.writer
            .write_to_known_channel(
                &header(self.stats),
                &serde_json::to_vec(frame.stats).map_err(mcap_error)?,
            )
            .map_err(mcap_error)?;
        if let Some(channel) = self.body {
            let bytes = f32_bytes(frame.body.vertices.iter().flatten().copied());
            self.writer
                .write_to_known_channel(&header(channel), &bytes)
                .map_err(mcap_error)?;
        }
        if let Some(scene) = &self.foxglove {
            let mut entities = vec![foxglove_entity(
                "garment",
                time_ns,
                frame.garment.iter().map(|p| [p.x, p.y, p.z]),
                &scene.garment_triangles,
                [0.24, 0.43, 0.8],
            )];
            if !scene.body_faces.is_empty() {
                entities.push(foxglove_entity(
                    "body",
                    time_ns,
                    frame.body.vertices.iter().copied(),
                    &scene.body_faces,
                    [0.81, 0.71, 0.65],
                ));
            }
            let message = serde_json::json!({"deletions": [], "entities": entities});
            self.writer
                .write_to_known_channel(
                    &header(scene.channel),
                    &serde_json::to_vec(&message).map_err(mcap_error)?,
                )
                .map_err(mcap_error)?;
        }
        Ok(())
    }

    /// Writes the summary and footer.
    pub fn finish(mut self) -> Result<()> {
        self.writer.finish().map_err(mcap_error)?;
        Ok(())
    }
}

/// A recording read back.
#[derive(Debug, Clone, Default)]
pub struct Recording {
    /// Sequence metadata.
    pub meta: Option<SequenceMeta>,
    /// The template.
    pub template: TemplateArrays,
    /// Garment vertices per frame, m.
    pub garment: Vec<Vec<[f32; 3]>>,
    /// Body pose per frame.
    pub poses: Vec<PoseRecord>,
    /// Body vertices per frame (empty if not recorded).
    pub body: Vec<Vec<[f32; 3]>>,
    /// Body triangles (empty if not recorded).
    pub body_faces: Vec<[u32; 3]>,
    /// Statistics per frame.
    pub stats: Vec<FrameStats>,
}

const MAGIC: &[u8] = b"\x89MCAP0\r\n";

impl Recording {
    /// Reads a whole recording; truncated or foreign files get an error naming the file.
    pub fn read(path: &Path) -> Result<Self> {
        let name = path.display().to_string();
        let fail = |message: String| Error::Recording {
            path: name.clone(),
            message,
        };
        let bytes = std::fs::read(path).map_err(|e| fail(e.to_string()))?;
        if !bytes.starts_with(MAGIC) {
            return Err(fail("not an MCAP file (no MCAP magic at the start)".into()));
        }
        if bytes.len() < 2 * MAGIC.len() || !bytes.ends_with(MAGIC) {
            return Err(fail(
                "truncated recording (no MCAP footer): the writer did not finish".into(),
            ));
        }
        let mut r = Recording::default();
        let stream = mcap::MessageStream::new(&bytes).map_err(|e| fail(e.to_string()))?;
        for message in stream {
            let m = message.map_err(|e| fail(e.to_string()))?;
            let data = &m.data;
            let topic = m.channel.topic.as_str();
            let json = |what: &str| fail(format!("bad {what} message on {topic}"));
            match topic {
                META_TOPIC => {
                    r.meta = Some(serde_json::from_slice(data).map_err(|_| json("metadata"))?)
                }
                TEMPLATE_POSITIONS_TOPIC => {
                    r.template.positions =
                        triples(data).iter().map(|p| p.map(|c| c as f64)).collect()
                }
                TEMPLATE_TRIANGLES_TOPIC => r.template.triangles = index_triples(data),
                TEMPLATE_UVS_TOPIC => {
                    r.template.uvs = floats(data)
                        .chunks_exact(2)
                        .map(|c| [c[0] as f64, c[1] as f64])
                        .collect()
                }
                TEMPLATE_UV_TRIANGLES_TOPIC => r.template.uv_triangles = index_triples(data),
                GARMENT_TOPIC => r.garment.push(triples(data)),
                POSE_TOPIC => r
                    .poses
                    .push(serde_json::from_slice(data).map_err(|_| json("pose"))?),
                BODY_VERTICES_TOPIC => r.body.push(triples(data)),
                BODY_FACES_TOPIC => r.body_faces = index_triples(data),
                STATS_TOPIC => r
                    .stats
                    .push(serde_json::from_slice(data).map_err(|_| json("statistics"))?),
                _ => {}
            }
        }
        let v = r.template.positions.len();
        if r.meta.is_none() || v == 0 {
            return Err(fail(
                "not a garment recording (no /sequence/meta or template)".into(),
            ));
        }
        if let Some(k) = r.garment.iter().position(|f| f.len() != v) {
            return Err(fail(format!(
                "frame {k} has {} garment vertices, the template {v}",
                r.garment[k].len()
            )));
        }
        if r.garment.iter().flatten().flatten().any(|c| !c.is_finite()) {
            return Err(fail("non-finite garment vertex".into()));
        }
        Ok(r)
    }
}

fn floats(data: &[u8]) -> Vec<f32> {
    data.chunks_exact(4)
        .map(|b| f32::from_le_bytes([b[0], b[1], b[2], b[3]]))
        .collect()
}

fn triples(data: &[u8]) -> Vec<[f32; 3]> {
    floats(data)
        .chunks_exact(3)
        .map(|c| [c[0], c[1], c[2]])
        .collect()
}

fn index_triples(data: &[u8]) -> Vec<[u32; 3]> {
    data.chunks_exact(12)
        .map(|b| {
            let u = |k: usize| u32::from_le_bytes([b[k], b[k + 1], b[k + 2], b[k + 3]]);
            [u(0), u(4), u(8)]
        })
        .collect()
}
