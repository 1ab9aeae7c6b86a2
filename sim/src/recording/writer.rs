//! The one MCAP writer of the project: garment sequences (the engine's and the surrogate's)
//! and body-only sequences, fed plain arrays frame by frame.

use std::collections::BTreeMap;
use std::io::{Seek, Write};

use mcap::records::{MessageHeader, Metadata};
use mcap::{Compression, WriteOptions};
use serde::Serialize;

use super::FrameStats;
use super::foxglove::{FOXGLOVE_SCENE_SCHEMA, FoxgloveScene, foxglove_entity};
use super::*;
use crate::error::{Error, Result};

const META_SCHEMA: &str = r#"{"title": "dit_garment.SequenceMeta", "type": "object", "description": "see docs/FORMATS.md"}"#;
const POSE_SCHEMA: &str = r#"{"title": "dit_garment.BodyPose", "type": "object", "properties": {"frame": {"type": "integer", "description": "frame index from 0"}, "time_s": {"type": "number", "description": "seconds since the first frame"}, "pose": {"type": "array", "items": {"type": "number"}, "minItems": 72, "maxItems": 72, "description": "SMPL axis-angle pose, radians: global_orient (3) then body_pose (69)"}, "transl": {"type": "array", "items": {"type": "number"}, "minItems": 3, "maxItems": 3, "description": "root translation, metres"}, "betas": {"type": "array", "items": {"type": "number"}, "description": "body shape of the frame (ramped during a blend-in)"}}, "required": ["frame", "time_s", "pose", "transl"]}"#;
const STATS_SCHEMA: &str = r#"{"title": "dit_garment.FrameStats", "type": "object", "description": "see docs/FORMATS.md"}"#;
const OCTET: &str = "application/octet-stream";

/// Which channels a sequence has besides the metadata and the body pose.
#[derive(Debug, Clone, Copy, Default)]
pub struct Channels<'a> {
    /// The garment template: a garment sequence (template once, vertices every frame).
    pub template: Option<&'a TemplateArrays>,
    /// Body triangles: body vertices every frame.
    pub body_faces: Option<&'a [[u32; 3]]>,
    /// Body joints every frame.
    pub joints: bool,
    /// Solver statistics every frame.
    pub stats: bool,
}

/// One frame as plain arrays. What the writer's [`Channels`] have must be given.
#[derive(Debug, Clone, Copy)]
pub struct FrameRecord<'a> {
    /// Frame index from 0.
    pub index: usize,
    /// Garment vertices, m (garment sequences).
    pub garment: Option<&'a [[f64; 3]]>,
    /// SMPL axis-angle pose, radians.
    pub pose: &'a [f64; 72],
    /// Root translation, m.
    pub transl: [f64; 3],
    /// Body shape of the frame.
    pub betas: &'a [f64],
    /// Body vertices, m.
    pub body_vertices: Option<&'a [[f64; 3]]>,
    /// Body joints, m.
    pub joints: Option<&'a [[f64; 3]]>,
    /// Solver statistics.
    pub stats: Option<&'a FrameStats>,
}

/// Streams a sequence into an MCAP file.
pub struct SequenceWriter<W: Write + Seek> {
    writer: mcap::Writer<W>,
    fps: f64,
    garment: Option<(u16, usize)>,
    pose: u16,
    stats: Option<u16>,
    body: Option<(u16, usize)>,
    joints: Option<u16>,
    foxglove: Option<FoxgloveScene>,
}

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

/// A message logged once at time 0.
fn once(channel_id: u16) -> MessageHeader {
    MessageHeader {
        channel_id,
        sequence: 0,
        log_time: 0,
        publish_time: 0,
    }
}

/// The metadata as an MCAP metadata record (string values, for tools that list metadata).
fn metadata_record(meta: &impl Serialize) -> Result<Metadata> {
    let mut info = BTreeMap::new();
    if let serde_json::Value::Object(map) = serde_json::to_value(meta).map_err(mcap_error)? {
        for (k, value) in map {
            let text = match value {
                serde_json::Value::String(s) => s,
                other => other.to_string(),
            };
            info.insert(k, text);
        }
    }
    Ok(Metadata {
        name: "sequence".to_string(),
        metadata: info,
    })
}

/// A raw array channel (`topic`, no schema) of `dtype` and `shape`.
fn array_channel<W: Write + Seek>(
    writer: &mut mcap::Writer<W>,
    topic: &str,
    dtype: &str,
    shape: String,
) -> Result<u16> {
    writer
        .add_channel(0, topic, OCTET, &raw(dtype, shape))
        .map_err(mcap_error)
}

/// The template's four array channels (their one message each queued in `once_arrays`) and
/// the per-frame garment channel: (its id, the vertex count).
fn template_channels<W: Write + Seek>(
    writer: &mut mcap::Writer<W>,
    t: &TemplateArrays,
    once_arrays: &mut Vec<(u16, Vec<u8>)>,
) -> Result<(u16, usize)> {
    let (v, f, u) = (t.positions.len(), t.triangles.len(), t.uvs.len());
    let positions = f32_bytes(t.positions.iter().flatten().copied());
    let uvs = f32_bytes(t.uvs.iter().flatten().copied());
    for (topic, dtype, shape, bytes) in [
        (TEMPLATE_POSITIONS_TOPIC, "float32", [v, 3], positions),
        (
            TEMPLATE_TRIANGLES_TOPIC,
            "uint32",
            [f, 3],
            u32_bytes(&t.triangles),
        ),
        (TEMPLATE_UVS_TOPIC, "float32", [u, 2], uvs),
        (
            TEMPLATE_UV_TRIANGLES_TOPIC,
            "uint32",
            [f, 3],
            u32_bytes(&t.uv_triangles),
        ),
    ] {
        let shape = format!("[{}, {}]", shape[0], shape[1]);
        once_arrays.push((array_channel(writer, topic, dtype, shape)?, bytes));
    }
    let garment = array_channel(writer, GARMENT_TOPIC, "float32", format!("[{v}, 3]"))?;
    Ok((garment, v))
}

impl<W: Write + Seek> SequenceWriter<W> {
    /// Starts a recording at `fps` frames per second: the metadata (a [`SequenceMeta`] for a
    /// garment sequence, a [`BodySequenceMeta`] for a body one), then what `channels` has.
    pub fn new(out: W, meta: &impl Serialize, channels: Channels, fps: f64) -> Result<Self> {
        let mut writer = WriteOptions::new()
            .compression(Some(Compression::Zstd))
            .chunk_size(Some(4 << 20))
            .profile("")
            .create(out)
            .map_err(mcap_error)?;
        let mut schema = |name: &str, text: &str| {
            writer
                .add_schema(name, "jsonschema", text.as_bytes())
                .map_err(mcap_error)
        };
        let meta_schema = schema("dit_garment.SequenceMeta", META_SCHEMA)?;
        let pose_schema = schema("dit_garment.BodyPose", POSE_SCHEMA)?;
        let stats_schema = schema("dit_garment.FrameStats", STATS_SCHEMA)?;
        let none = BTreeMap::new();
        let meta_channel = writer
            .add_channel(meta_schema, META_TOPIC, "json", &none)
            .map_err(mcap_error)?;
        let mut once_arrays: Vec<(u16, Vec<u8>)> = Vec::new();
        let garment = match channels.template {
            Some(t) => Some(template_channels(&mut writer, t, &mut once_arrays)?),
            None => None,
        };
        let pose = writer
            .add_channel(pose_schema, POSE_TOPIC, "json", &none)
            .map_err(mcap_error)?;
        let stats = match channels.stats {
            true => Some(
                writer
                    .add_channel(stats_schema, STATS_TOPIC, "json", &none)
                    .map_err(mcap_error)?,
            ),
            false => None,
        };
        let mut body = None;
        if let Some(faces) = channels.body_faces {
            let nv = faces.iter().flatten().max().map_or(0, |&m| m as usize + 1);
            let vertices = array_channel(
                &mut writer,
                BODY_VERTICES_TOPIC,
                "float32",
                format!("[{nv}, 3]"),
            )?;
            let shape = format!("[{}, 3]", faces.len());
            let faces_channel = array_channel(&mut writer, BODY_FACES_TOPIC, "uint32", shape)?;
            once_arrays.push((faces_channel, u32_bytes(faces)));
            body = Some((vertices, nv));
        }
        let joints = match channels.joints {
            true => Some(array_channel(
                &mut writer,
                BODY_JOINTS_TOPIC,
                "float32",
                "[24, 3]".to_string(),
            )?),
            false => None,
        };
        writer
            .write_metadata(&metadata_record(meta)?)
            .map_err(mcap_error)?;
        let meta_json = serde_json::to_vec(meta).map_err(mcap_error)?;
        writer
            .write_to_known_channel(&once(meta_channel), &meta_json)
            .map_err(mcap_error)?;
        for (channel, bytes) in once_arrays {
            writer
                .write_to_known_channel(&once(channel), &bytes)
                .map_err(mcap_error)?;
        }
        Ok(Self {
            writer,
            fps,
            garment,
            pose,
            stats,
            body,
            joints,
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

    /// Appends one frame; an array the writer's channels need and the frame lacks, or one of
    /// the wrong length, is an error.
    pub fn write_frame(&mut self, frame: &FrameRecord) -> Result<()> {
        let k = frame.index;
        let time_ns = (k as f64 / self.fps * 1e9).round() as u64;
        let header = |channel_id| MessageHeader {
            channel_id,
            sequence: k as u32,
            log_time: time_ns,
            publish_time: time_ns,
        };
        let missing = |what: &str, expected: usize, got: Option<usize>| {
            mcap_error(format!(
                "frame {k}: {what} has {} values, the recording expects {expected}",
                got.map_or("no".to_string(), |n| n.to_string())
            ))
        };
        let mut arrays: Vec<(u16, Vec<u8>)> = Vec::new();
        if let Some((channel, v)) = self.garment {
            let garment = frame
                .garment
                .filter(|g| g.len() == v)
                .ok_or_else(|| missing("the garment", v, frame.garment.map(<[_]>::len)))?;
            arrays.push((channel, f32_bytes(garment.iter().flatten().copied())));
        }
        let pose = PoseRecord {
            frame: k,
            time_s: k as f64 / self.fps,
            pose: frame.pose.to_vec(),
            transl: frame.transl,
            betas: frame.betas.to_vec(),
        };
        let pose = serde_json::to_vec(&pose).map_err(mcap_error)?;
        for (channel, bytes) in arrays {
            self.writer
                .write_to_known_channel(&header(channel), &bytes)
                .map_err(mcap_error)?;
        }
        self.writer
            .write_to_known_channel(&header(self.pose), &pose)
            .map_err(mcap_error)?;
        if let Some(channel) = self.stats {
            let stats = frame.stats.ok_or_else(|| missing("stats", 1, None))?;
            self.writer
                .write_to_known_channel(
                    &header(channel),
                    &serde_json::to_vec(stats).map_err(mcap_error)?,
                )
                .map_err(mcap_error)?;
        }
        if let Some((channel, n)) = self.body {
            let body = frame
                .body_vertices
                .filter(|b| b.len() == n)
                .ok_or_else(|| missing("the body", n, frame.body_vertices.map(<[_]>::len)))?;
            let bytes = f32_bytes(body.iter().flatten().copied());
            self.writer
                .write_to_known_channel(&header(channel), &bytes)
                .map_err(mcap_error)?;
        }
        if let Some(channel) = self.joints {
            let joints = frame
                .joints
                .filter(|j| j.len() == 24)
                .ok_or_else(|| missing("the joints", 24, frame.joints.map(<[_]>::len)))?;
            let bytes = f32_bytes(joints.iter().flatten().copied());
            self.writer
                .write_to_known_channel(&header(channel), &bytes)
                .map_err(mcap_error)?;
        }
        if let Some(scene) = &self.foxglove {
            let garment = frame.garment.unwrap_or_default();
            let mut entities = vec![foxglove_entity(
                "garment",
                time_ns,
                garment.iter().copied(),
                &scene.garment_triangles,
                [0.24, 0.43, 0.8],
            )];
            if let Some(body) = frame.body_vertices
                && !scene.body_faces.is_empty()
            {
                entities.push(foxglove_entity(
                    "body",
                    time_ns,
                    body.iter().copied(),
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
