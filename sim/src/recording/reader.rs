//! Reading a garment recording back whole: metadata, template, frames, poses, body and
//! statistics, with an error naming the file for anything truncated or foreign.

use std::path::Path;

use motions::BodyModel;

use super::FrameStats;
use super::mcap_read::{MAGIC, messages};
use super::*;
use crate::error::{Error, Result};

/// A recording read back.
#[derive(Debug, Clone, Default)]
pub struct Recording {
    /// Sequence metadata.
    pub meta: Option<SequenceMeta>,
    /// The metadata message as written, with any keys a writer added beside the sequence's
    /// (a prediction's `predicted`: model and sampler settings).
    pub meta_json: Option<serde_json::Value>,
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

/// The body of one recorded frame.
#[derive(Debug, Clone)]
pub struct RecordedBody {
    /// Vertex positions, m.
    pub vertices: Vec<[f64; 3]>,
    /// Triangles.
    pub faces: Vec<[u32; 3]>,
}

impl Recording {
    /// The scene configuration the recording at `path` was simulated from, to simulate or
    /// predict it again (`--config-from`); refused for a recording without one (a predicted
    /// sequence, or one made before configurations were recorded).
    pub fn scene_config(path: &Path) -> Result<SceneConfig> {
        let fail = |message: &str| Error::Recording {
            path: path.display().to_string(),
            message: message.to_string(),
        };
        let meta = Self::read(path)?
            .meta
            .ok_or_else(|| fail("the recording has no metadata"))?;
        meta.scene_config().ok_or_else(|| {
            fail(
                "the recording carries no scene configuration (made by an older version, or a \
                 predicted sequence); pass the scene's flags or a --config file instead",
            )
        })
    }

    /// The body of frame `k`: the recorded vertices if the recording has them, else `model`
    /// posed with the frame's recorded pose, translation and shape. The triangles (recorded,
    /// else the model's) are checked against the vertex count, so a wrong body model is
    /// named; `path` names the recording in errors.
    pub fn body_at(&self, model: &BodyModel, k: usize, path: &Path) -> Result<RecordedBody> {
        let fail = |message: String| Error::Recording {
            path: path.display().to_string(),
            message,
        };
        let vertices = if let Some(v) = self.body.get(k) {
            v.iter().map(|p| p.map(|c| c as f64)).collect()
        } else {
            let pose = self
                .poses
                .get(k)
                .ok_or_else(|| fail(format!("frame {k} has no body pose")))?;
            let pose_values: [f64; 72] = pose.pose.as_slice().try_into().map_err(|_| {
                fail(format!(
                    "frame {k} has {} pose values, not 72",
                    pose.pose.len()
                ))
            })?;
            let shaped = model.shape(&pose.betas)?;
            let frame = motions::FramePose {
                pose: pose_values,
                transl: pose.transl,
            };
            model.pose(&shaped, &frame)?.vertices
        };
        let faces = if self.body_faces.is_empty() {
            model.faces().to_vec()
        } else {
            self.body_faces.clone()
        };
        if faces
            .iter()
            .flatten()
            .any(|&i| i as usize >= vertices.len())
        {
            return Err(fail(
                "the body model does not match the recording's body (pass the right --body-model)"
                    .into(),
            ));
        }
        Ok(RecordedBody { vertices, faces })
    }

    /// Reads a whole recording; truncated or foreign files get an error naming the file.
    pub fn read(path: &Path) -> Result<Self> {
        let bytes = files::read(path, files::limits::RECORDING, "recording")?;
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
        for (topic, data) in messages(bytes).map_err(&fail)? {
            let data = &data;
            let topic = topic.as_str();
            let json = |what: &str| fail(format!("bad {what} message on {topic}"));
            match topic {
                META_TOPIC => {
                    let value: serde_json::Value =
                        serde_json::from_slice(data).map_err(|_| json("metadata"))?;
                    r.meta =
                        Some(serde_json::from_value(value.clone()).map_err(|_| json("metadata"))?);
                    r.meta_json = Some(value);
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

#[cfg(test)]
mod tests {
    use super::*;
    use crate::params::{Material, SolverParams};
    use crate::recording::mcap_read::chunk_ranges;
    use crate::recording::{Channels, FrameRecord, SequenceWriter};
    use rand::{Rng, SeedableRng};

    /// A small garment recording (one noisy 300-vertex sheet over 20 frames) in memory.
    fn recording() -> Vec<u8> {
        let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(7);
        let positions: Vec<[f64; 3]> = (0..300)
            .map(|_| [rng.random(), rng.random(), rng.random()])
            .collect();
        let template = TemplateArrays {
            positions: positions.clone(),
            triangles: (0..299).map(|k| [k, k + 1, (k + 2) % 300]).collect(),
            uvs: vec![],
            uv_triangles: vec![],
        };
        let meta = SequenceMeta {
            software: "test".into(),
            garment: "sheet".into(),
            motion: "none".into(),
            body_model: "none".into(),
            betas: vec![0.0; 10],
            fps: 30.0,
            frames: 20,
            blend_frames: 0,
            settle_frames: 0,
            material: Material::default(),
            friction: 0.3,
            seed: None,
            solver: SolverParams::default(),
            units: "m".into(),
            config: None,
        };
        let mut bytes = std::io::Cursor::new(Vec::new());
        let channels = Channels {
            template: Some(&template),
            ..Default::default()
        };
        let mut writer = SequenceWriter::new(&mut bytes, &meta, channels, 30.0).unwrap();
        for index in 0..20 {
            let garment: Vec<[f64; 3]> = positions
                .iter()
                .map(|p| [p[0], p[1] - 0.01 * index as f64, p[2]])
                .collect();
            let frame = FrameRecord {
                index,
                garment: Some(&garment),
                pose: &[0.0; 72],
                transl: [0.0; 3],
                betas: &[0.0; 10],
                body_vertices: None,
                joints: None,
                stats: None,
            };
            writer.write_frame(&frame).unwrap();
        }
        writer.finish().unwrap();
        bytes.into_inner()
    }

    fn read(bytes: &[u8]) -> Result<Recording> {
        Recording::from_bytes(bytes, Path::new("damaged.mcap"))
    }

    #[test]
    fn an_intact_recording_reads_back() {
        let r = read(&recording()).unwrap();
        assert_eq!(r.garment.len(), 20);
        assert_eq!(r.template.positions.len(), 300);
    }

    #[test]
    fn damage_inside_a_chunk_is_named_with_the_chunk() {
        let bytes = recording();
        let chunks = chunk_ranges(&bytes).unwrap();
        for (k, chunk) in chunks.iter().enumerate() {
            let mut bytes = bytes.clone();
            let middle = ((chunk.start + chunk.end) / 2) as usize;
            for b in &mut bytes[middle..middle + 32] {
                *b ^= 0x5a;
            }
            let message = read(&bytes).unwrap_err().to_string();
            assert!(message.contains("damaged.mcap"), "{message}");
            let named = format!("chunk {k} of {}", chunks.len());
            assert!(message.contains(&named), "{message}");
        }
    }

    #[test]
    fn a_huge_length_field_is_an_error_not_an_abort() {
        let mut bytes = recording();
        let chunk = chunk_ranges(&bytes).unwrap()[0].clone();
        // The chunk header's uncompressed size follows opcode, length and two times.
        let size_at = chunk.start as usize + 9 + 16;
        bytes[size_at..size_at + 8].copy_from_slice(&(u64::MAX / 3).to_le_bytes());
        let message = read(&bytes).unwrap_err().to_string();
        assert!(message.contains("chunk 0"), "{message}");
        // A record length past the end of the file.
        let mut bytes = recording();
        bytes[9..17].copy_from_slice(&0x7000_0000_0000_0000u64.to_le_bytes());
        let message = read(&bytes).unwrap_err().to_string();
        assert!(message.contains("past the end of the file"), "{message}");
    }

    /// Found by the `recording` fuzz target: a metadata record whose map claims 4 GB. mcap's
    /// record parser reserved it; the reader must not parse such records at all.
    #[test]
    fn a_metadata_record_claiming_gigabytes_is_refused_without_reserving_them() {
        let bytes: &[u8] = &[
            137, 77, 67, 65, 80, 48, 13, 10, 12, 66, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 254, 255,
            255, 255, 255, 255, 255, 255, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0,
            0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0,
            59, 77, 64, 65, 0, 230, 137, 77, 67, 65, 80, 48, 13, 10,
        ];
        let message = read(bytes).unwrap_err().to_string();
        assert!(message.contains("damaged.mcap"), "{message}");
    }

    /// Found by the `recording` fuzz target: an uncompressed chunk without a CRC whose inner
    /// record runs past the chunk (mcap's reader then subtracts past zero).
    #[test]
    fn a_chunk_whose_record_runs_past_it_is_refused() {
        let mut bytes = MAGIC.to_vec();
        bytes.extend_from_slice(&[0, 0, 0, 0, 0, 0, 0, 0, 0]);
        let mut chunk = vec![0u8; 24];
        chunk.extend_from_slice(&0x1234u32.to_le_bytes()); // CRC
        chunk.extend_from_slice(&0u32.to_le_bytes()); // no compression
        chunk.extend_from_slice(&20u64.to_le_bytes()); // records length
        chunk.push(0x05);
        chunk.extend_from_slice(&200u64.to_le_bytes()); // a message longer than the chunk
        chunk.extend_from_slice(&[0; 11]);
        bytes.push(0x06);
        bytes.extend_from_slice(&(chunk.len() as u64).to_le_bytes());
        bytes.extend_from_slice(&chunk);
        bytes.extend_from_slice(MAGIC);
        let message = read(&bytes).unwrap_err().to_string();
        assert!(message.contains("runs past the chunk"), "{message}");
        // The same chunk without a CRC (the input the fuzzer found) is refused for that.
        let crc_at = MAGIC.len() + 9 + 9 + 24;
        bytes[crc_at..crc_at + 4].fill(0);
        let message = read(&bytes).unwrap_err().to_string();
        assert!(message.contains("no CRC"), "{message}");
    }

    /// Random damage of 1-8 bytes, 200 seeded cases: each is read without a panic, and a
    /// file that still reads has the original vertices (no silent change).
    #[test]
    fn random_damage_never_panics_or_changes_vertices_silently() {
        let original = recording();
        let truth = read(&original).unwrap();
        let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(27);
        let mut refused = 0;
        for case in 0..200 {
            let mut bytes = original.clone();
            for _ in 0..rng.random_range(1..=8) {
                let at = rng.random_range(0..bytes.len());
                bytes[at] ^= rng.random_range(1..=255u8);
            }
            let result = std::panic::catch_unwind(|| read(&bytes));
            let Ok(result) = result else {
                panic!("case {case} panicked");
            };
            match result {
                Ok(r) => assert_eq!(r.garment, truth.garment, "case {case} changed vertices"),
                Err(_) => refused += 1,
            }
        }
        assert!(refused > 100, "only {refused} of 200 damaged files refused");
    }
}
