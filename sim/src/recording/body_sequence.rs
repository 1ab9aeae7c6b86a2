//! A body-only sequence (`motions export`): a motion posed on a shaped body, every frame's
//! pose, joints and vertices recorded with the body's triangles, through the same writer as a
//! garment sequence.

use std::path::Path;

use motions::{BlendIn, BodyModel, Motion, canonical_a_pose};

use super::{BodySequenceMeta, Channels, FrameRecord, SequenceWriter, UNITS};
use crate::error::Result;

/// Records `motion` on `model` shaped by `betas` into `path`, atomically, after a blend-in
/// from the canonical A-pose when `blend` asks for one; returns the recording's metadata.
pub fn write_body_sequence(
    path: &Path,
    model: &BodyModel,
    betas: &[f64],
    motion: &Motion,
    blend: BlendIn,
    software: &str,
) -> Result<BodySequenceMeta> {
    let shaped = model.shape(betas)?;
    let blended;
    let motion = if blend.blend_frames + blend.settle_frames > 0 {
        blended = motion.with_blend_in(&canonical_a_pose(), blend);
        &blended
    } else {
        motion
    };
    let posed = model.pose_batch(&shaped, &motion.frames)?;
    let meta = BodySequenceMeta {
        software: software.to_string(),
        motion: motion.name.clone(),
        body_model: model.name().to_string(),
        betas: shaped.betas.clone(),
        fps: motion.fps,
        frames: motion.len(),
        blend_frames: blend.blend_frames,
        settle_frames: blend.settle_frames,
        units: UNITS.to_string(),
    };
    let channels = Channels {
        body_faces: Some(model.faces()),
        joints: true,
        ..Channels::default()
    };
    let write = |w: &mut std::io::BufWriter<std::fs::File>| -> Result<()> {
        let mut writer = SequenceWriter::new(w, &meta, channels, motion.fps)?;
        for (index, (frame, body)) in motion.frames.iter().zip(&posed).enumerate() {
            writer.write_frame(&FrameRecord {
                index,
                garment: None,
                pose: &frame.pose,
                transl: frame.transl,
                betas: &shaped.betas,
                body_vertices: Some(&body.vertices),
                joints: Some(&body.joints),
                stats: None,
            })?;
        }
        writer.finish()
    };
    files::create_folder_of(path)?;
    files::write_fallible(path, write)?;
    Ok(meta)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::recording::{BODY_VERTICES_TOPIC, META_TOPIC, mcap_read::messages};

    #[test]
    fn a_body_sequence_holds_its_blend_in_and_shape() {
        let model = BodyModel::default_body();
        let betas = [0.5, -1.0];
        let shaped = model.shape(&betas).unwrap();
        let walk = motions::library::MotionSpec::parse("walk:duration=0.2")
            .unwrap()
            .generate(&model, &shaped)
            .unwrap();
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("new/body.mcap");
        let blend = BlendIn {
            blend_frames: 3,
            settle_frames: 2,
        };
        let meta = write_body_sequence(&path, &model, &betas, &walk, blend, "test").unwrap();
        assert_eq!(meta.frames, walk.len() + 5);
        let all = messages(&std::fs::read(&path).unwrap()).unwrap();
        let of = |topic: &'static str| all.iter().filter(move |(t, _)| t == topic).map(|(_, d)| d);
        let stored: BodySequenceMeta =
            serde_json::from_slice(of(META_TOPIC).next().unwrap()).unwrap();
        assert_eq!(stored, meta);
        assert_eq!(of(BODY_VERTICES_TOPIC).count(), meta.frames);
        // Frame 0 is the shaped body in the canonical A-pose.
        let first: Vec<f32> = of(BODY_VERTICES_TOPIC)
            .next()
            .unwrap()
            .chunks_exact(4)
            .map(|b| f32::from_le_bytes(b.try_into().unwrap()))
            .collect();
        let pose = motions::FramePose {
            pose: canonical_a_pose(),
            transl: walk.frames[0].transl,
        };
        let posed = model.pose(&shaped, &pose).unwrap();
        let worst = posed
            .vertices
            .iter()
            .flatten()
            .zip(&first)
            .map(|(a, &b)| (a - f64::from(b)).abs())
            .fold(0.0, f64::max);
        assert!(worst < 1e-5, "{worst} m");
    }
}
