//! Body sequences as MCAP files (one per sequence); channels and schemas are documented in
//! docs/FORMATS.md. Raw arrays are little-endian with `dtype` and `shape` in channel metadata,
//! so the Python `mcap` package and Foxglove read them without our code.

use std::collections::BTreeMap;
use std::io::{Seek, Write};

use anyhow::Result;
use mcap::records::{MessageHeader, Metadata};
use mcap::{Compression, WriteOptions};
use motions::{BodyModel, Motion, PosedBody, ShapedBody};
use serde_json::json;

/// Topic of the per-frame pose message (JSON).
pub const POSE_TOPIC: &str = "/body/pose";
/// Topic of the per-frame vertex array (float32, V x 3).
pub const VERTICES_TOPIC: &str = "/body/vertices";
/// Topic of the per-frame joint array (float32, 24 x 3).
pub const JOINTS_TOPIC: &str = "/body/joints";
/// Topic of the one-off triangle array (uint32, F x 3), logged at time 0.
pub const FACES_TOPIC: &str = "/body/faces";

const POSE_SCHEMA: &str = r#"{
  "title": "dit_garment.BodyPose",
  "type": "object",
  "properties": {
    "frame": {"type": "integer", "description": "frame index from 0"},
    "time_s": {"type": "number", "description": "seconds since the first frame"},
    "pose": {"type": "array", "items": {"type": "number"}, "minItems": 72, "maxItems": 72, "description": "SMPL axis-angle pose, radians: global_orient (3) then body_pose (69)"},
    "transl": {"type": "array", "items": {"type": "number"}, "minItems": 3, "maxItems": 3, "description": "root translation, metres"}
  },
  "required": ["frame", "time_s", "pose", "transl"]
}"#;

/// Writes a posed body sequence: poses, joints and vertices for every frame.
pub fn write_body_sequence<W: Write + Seek>(
    out: W,
    model: &BodyModel,
    shaped: &ShapedBody,
    motion: &Motion,
    posed: &[PosedBody],
    extra: &BTreeMap<String, String>,
) -> Result<()> {
    let mut writer = WriteOptions::new()
        .compression(Some(Compression::Zstd))
        .chunk_size(Some(4 << 20))
        .profile("")
        .create(out)?;
    let schema = writer.add_schema("dit_garment.BodyPose", "jsonschema", POSE_SCHEMA.as_bytes())?;
    let raw = |dtype: &str, shape: String| {
        BTreeMap::from([
            ("dtype".to_string(), dtype.to_string()),
            ("shape".to_string(), shape),
            ("byte_order".to_string(), "little".to_string()),
        ])
    };
    let nv = model.num_vertices();
    let pose_channel = writer.add_channel(schema, POSE_TOPIC, "json", &BTreeMap::new())?;
    let vertex_channel = writer.add_channel(
        0,
        VERTICES_TOPIC,
        "application/octet-stream",
        &raw("float32", format!("[{nv}, 3]")),
    )?;
    let joint_channel = writer.add_channel(
        0,
        JOINTS_TOPIC,
        "application/octet-stream",
        &raw("float32", "[24, 3]".to_string()),
    )?;
    let face_channel = writer.add_channel(
        0,
        FACES_TOPIC,
        "application/octet-stream",
        &raw("uint32", format!("[{}, 3]", model.faces().len())),
    )?;

    let mut info = BTreeMap::from([
        ("motion".to_string(), motion.name.clone()),
        ("fps".to_string(), motion.fps.to_string()),
        ("frames".to_string(), motion.len().to_string()),
        ("body_model".to_string(), model.name().to_string()),
        ("betas".to_string(), serde_json::to_string(&shaped.betas)?),
        (
            "units".to_string(),
            "metres, seconds, radians; y up".to_string(),
        ),
        (
            "software".to_string(),
            format!("dit-garment {}", env!("CARGO_PKG_VERSION")),
        ),
    ]);
    info.extend(extra.clone());
    writer.write_metadata(&Metadata {
        name: "sequence".to_string(),
        metadata: info,
    })?;

    let faces: Vec<u8> = model
        .faces()
        .iter()
        .flatten()
        .flat_map(|i| i.to_le_bytes())
        .collect();
    writer.write_to_known_channel(
        &MessageHeader {
            channel_id: face_channel,
            sequence: 0,
            log_time: 0,
            publish_time: 0,
        },
        &faces,
    )?;
    for (k, (frame, body)) in motion.frames.iter().zip(posed).enumerate() {
        let time_ns = (k as f64 / motion.fps * 1e9).round() as u64;
        let header = |channel_id| MessageHeader {
            channel_id,
            sequence: k as u32,
            log_time: time_ns,
            publish_time: time_ns,
        };
        let pose = json!({"frame": k, "time_s": k as f64 / motion.fps, "pose": frame.pose.to_vec(), "transl": frame.transl});
        writer.write_to_known_channel(&header(pose_channel), &serde_json::to_vec(&pose)?)?;
        writer.write_to_known_channel(
            &header(vertex_channel),
            &f32_bytes(body.vertices.iter().flatten()),
        )?;
        writer.write_to_known_channel(
            &header(joint_channel),
            &f32_bytes(body.joints.iter().flatten()),
        )?;
    }
    writer.finish()?;
    Ok(())
}

fn f32_bytes<'a>(values: impl Iterator<Item = &'a f64>) -> Vec<u8> {
    values.flat_map(|&v| (v as f32).to_le_bytes()).collect()
}
