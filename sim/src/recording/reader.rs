//! Reading a garment recording back whole: metadata, template, frames, poses, body and
//! statistics, with an error naming the file for anything truncated or foreign.

use std::path::Path;

use super::*;
use crate::error::{Error, Result};
use crate::scene::FrameStats;

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
        let bytes = std::fs::read(path).map_err(|e| Error::Recording {
            path: path.display().to_string(),
            message: e.to_string(),
        })?;
        Self::from_bytes(&bytes, path)
    }

    /// Parses a recording already in memory (a caller that also checksums the file reads it
    /// once); `path` names it in errors.
    pub fn from_bytes(bytes: &[u8], path: &Path) -> Result<Self> {
        let name = path.display().to_string();
        let fail = |message: String| Error::Recording {
            path: name.clone(),
            message,
        };
        if !bytes.starts_with(MAGIC) {
            return Err(fail("not an MCAP file (no MCAP magic at the start)".into()));
        }
        if bytes.len() < 2 * MAGIC.len() || !bytes.ends_with(MAGIC) {
            return Err(fail(
                "truncated recording (no MCAP footer): the writer did not finish".into(),
            ));
        }
        let mut r = Recording::default();
        let stream = mcap::MessageStream::new(bytes).map_err(|e| fail(e.to_string()))?;
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
