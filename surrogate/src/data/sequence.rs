//! A recorded garment sequence as the surrogate uses it: the template, and per frame the body
//! (pose, translation, shape) and the cloth, read through `sim::recording`; and the UV
//! round-trip floor of a sequence (encode the ground truth, read it back, score it: the best
//! any UV model can do at that resolution).

use std::path::Path;

use motions::{BodyModel, FramePose, Motion, POSE_DIM};
use sim::recording::{Recording, SequenceMeta, TemplateArrays};

use crate::error::{Error, Result};
use crate::geometry::{FrameBody, GeometryImage, Targets};

/// A garment sequence read back.
#[derive(Debug, Clone)]
pub struct Sequence {
    /// The file it was read from, for errors.
    pub source: String,
    /// The recording's metadata.
    pub meta: SequenceMeta,
    /// The template.
    pub template: TemplateArrays,
    /// Body pose and root translation per frame.
    pub poses: Vec<FramePose>,
    /// Body shape per frame.
    pub betas: Vec<Vec<f64>>,
    /// Garment vertices per frame, m.
    pub garment: Vec<Vec<[f64; 3]>>,
}

impl Sequence {
    /// Reads a garment recording; a missing, damaged or foreign file is an error naming it.
    pub fn read(path: &Path) -> Result<Self> {
        Self::from_recording(Recording::read(path)?, path)
    }

    /// A sequence from a recording already read; `path` names it in errors.
    pub fn from_recording(r: Recording, path: &Path) -> Result<Self> {
        let name = path.display().to_string();
        let fail = |problem: String| Error::File {
            path: name.clone(),
            problem: problem.into(),
        };
        let meta = r
            .meta
            .ok_or_else(|| fail("the recording has no metadata".into()))?;
        // The conditions take log10 k_b and scale k_s and rho: a bad value would be NaN there.
        meta.material
            .validate()
            .map_err(|e| fail(format!("the recorded material is unusable: {e}")))?;
        if r.template.uv_triangles.len() != r.template.triangles.len() || r.template.uvs.is_empty()
        {
            return Err(fail("the template has no UVs".into()));
        }
        if r.poses.len() != r.garment.len() {
            return Err(fail(format!(
                "{} body poses for {} garment frames",
                r.poses.len(),
                r.garment.len()
            )));
        }
        let mut poses = Vec::with_capacity(r.poses.len());
        let mut betas = Vec::with_capacity(r.poses.len());
        for (k, p) in r.poses.iter().enumerate() {
            let pose: [f64; POSE_DIM] = p.pose.as_slice().try_into().map_err(|_| {
                fail(format!(
                    "frame {k} has {} pose values, not {POSE_DIM}",
                    p.pose.len()
                ))
            })?;
            poses.push(FramePose {
                pose,
                transl: p.transl,
            });
            betas.push(p.betas.clone());
        }
        let garment = r
            .garment
            .iter()
            .map(|f| f.iter().map(|p| p.map(f64::from)).collect())
            .collect();
        Ok(Self {
            source: name,
            meta,
            template: r.template,
            poses,
            betas,
            garment,
        })
    }

    /// Frames recorded.
    pub fn len(&self) -> usize {
        self.garment.len()
    }

    /// Whether no frame was recorded.
    pub fn is_empty(&self) -> bool {
        self.garment.is_empty()
    }

    /// The first frame of the motion proper (after the blend-in and settle frames): the
    /// frames a model learns from and is scored on.
    pub fn first_motion_frame(&self) -> usize {
        (self.meta.blend_frames + self.meta.settle_frames).min(self.len().saturating_sub(1))
    }

    /// The motion the body followed (blend-in included), for pose windows.
    pub fn motion(&self) -> Result<Motion> {
        Ok(Motion::new(
            self.meta.motion.clone(),
            self.meta.fps,
            self.poses.clone(),
        )?)
    }

    /// The body of frame `k`.
    pub fn body(&self, k: usize) -> FrameBody<'_> {
        FrameBody {
            pose: &self.poses[k],
            betas: &self.betas[k],
        }
    }
}

/// The round-trip floor of a sequence at one resolution and target.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Floor {
    /// Frames scored (every `stride`-th motion frame).
    pub frames_scored: usize,
    /// Mean over frames of the mean vertex distance, cm (E_v of the round trip).
    pub mean_cm: f64,
    /// 95th percentile of vertex distances over the scored frames, cm.
    pub p95_cm: f64,
    /// Largest vertex distance, cm.
    pub max_cm: f64,
    /// The vertex of the largest distance.
    pub worst_vertex: usize,
    /// Mean target magnitude, cm (what a model must predict).
    pub target_mean_cm: f64,
}

/// Encodes every `stride`-th motion frame's target, reads it back, decodes it and measures the
/// distance to the recorded cloth.
pub fn roundtrip_floor(
    model: &BodyModel,
    sequence: &Sequence,
    image: &GeometryImage,
    targets: &mut Targets,
    stride: usize,
) -> Result<Floor> {
    let mut distances = Vec::new();
    let mut frame_means = Vec::new();
    let mut magnitude = (0.0, 0usize);
    let mut worst = (0.0f64, 0usize);
    for k in (sequence.first_motion_frame()..sequence.len()).step_by(stride.max(1)) {
        let body = sequence.body(k);
        let truth = &sequence.garment[k];
        let target = targets.encode(model, body, truth)?;
        for t in &target {
            magnitude.0 += (t[0] * t[0] + t[1] * t[1] + t[2] * t[2]).sqrt();
            magnitude.1 += 1;
        }
        let read = image.read(&image.encode(&target)?)?;
        let cloth = targets.decode(model, body, &read)?;
        let mut sum = 0.0;
        for (v, (a, b)) in cloth.iter().zip(truth).enumerate() {
            let d = 100.0
                * ((a[0] - b[0]).powi(2) + (a[1] - b[1]).powi(2) + (a[2] - b[2]).powi(2)).sqrt();
            if d > worst.0 {
                worst = (d, v);
            }
            sum += d;
            distances.push(d);
        }
        frame_means.push(sum / truth.len().max(1) as f64);
    }
    if frame_means.is_empty() {
        return Err(Error::File {
            path: sequence.source.clone(),
            problem: format!(
                "'{}' on '{}' has no motion frames to score ({} frames, all of them blend-in \
                 and settle)",
                sequence.meta.garment,
                sequence.meta.motion,
                sequence.len()
            )
            .into(),
        });
    }
    distances.sort_by(f64::total_cmp);
    let p95 = distances[((distances.len() as f64 * 0.95) as usize).min(distances.len() - 1)];
    Ok(Floor {
        frames_scored: frame_means.len(),
        mean_cm: frame_means.iter().sum::<f64>() / frame_means.len() as f64,
        p95_cm: p95,
        max_cm: worst.0,
        worst_vertex: worst.1,
        target_mean_cm: 100.0 * magnitude.0 / magnitude.1.max(1) as f64,
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    fn recording(k_b: f64) -> Recording {
        let meta = serde_json::json!({
            "software": "test", "garment": "g", "motion": "m", "body_model": "default",
            "betas": [], "fps": 30.0, "frames": 0, "blend_frames": 0, "settle_frames": 0,
            "material": {"k_s_n_per_m": 100.0, "rho_kg_per_m2": 0.2, "k_b_n_m": 1e-5},
            "friction": 0.3, "seed": null, "solver": sim::SolverParams::default(),
            "units": sim::recording::UNITS,
        });
        let mut meta: SequenceMeta = serde_json::from_value(meta).unwrap();
        meta.material.bending = k_b;
        Recording {
            meta: Some(meta),
            template: TemplateArrays {
                positions: vec![[0.0; 3]; 3],
                triangles: vec![[0, 1, 2]],
                uvs: vec![[0.0; 2]; 3],
                uv_triangles: vec![[0, 1, 2]],
            },
            ..Recording::default()
        }
    }

    #[test]
    fn a_recorded_material_that_is_not_positive_is_refused_naming_file_and_key() {
        assert!(Sequence::from_recording(recording(1e-5), Path::new("ok.mcap")).is_ok());
        for k_b in [0.0, -1e-5, f64::NAN] {
            let error = Sequence::from_recording(recording(k_b), Path::new("bad.mcap"))
                .unwrap_err()
                .to_string();
            assert!(
                error.contains("bad.mcap") && error.contains("k_b_n_m"),
                "{k_b}: {error}"
            );
        }
    }
}
