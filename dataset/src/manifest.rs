//! What a dataset records per sequence (one manifest line), the quality gates, and the
//! statistics over a manifest.

use serde::{Deserialize, Serialize};

use super::plan::PlannedSequence;
use super::spec::GateSpec;
use super::split::Status;

use sim::SolverParams;
use sim::scene::RunSummary;

/// Gate results of one attempt.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct GateResult {
    /// Every value finite.
    pub finite: bool,
    /// Deepest vertex inside the body over all frames, away from where the body overlaps
    /// itself (the gated figure), m; NaN (`null`) for an unfinished attempt.
    #[serde(deserialize_with = "nan_if_null")]
    pub max_penetration_m: f64,
    /// Most vertices inside the body in one frame, away from body overlaps.
    pub max_verts_inside: usize,
    /// Deepest vertex inside the body where it overlaps itself, m (reported, not gated).
    #[serde(default, deserialize_with = "nan_if_null")]
    pub max_penetration_overlap_m: f64,
    /// Most vertices inside the body in one frame where it overlaps itself.
    #[serde(default)]
    pub max_verts_inside_overlap: usize,
    /// Largest edge stretch; NaN (`null`) for an unfinished attempt.
    #[serde(deserialize_with = "nan_if_null")]
    pub max_edge_stretch: f64,
    /// Most crossing garment triangle pairs in one frame.
    #[serde(default)]
    pub max_self_intersections: usize,
    /// The attempt ran past the time limit.
    pub timed_out: bool,
    /// Whether every gate passed.
    pub passed: bool,
    /// The gates that failed, with measured value and limit.
    pub failed: Vec<String>,
}

/// A figure JSON wrote as `null` (serde_json's NaN) read back as NaN.
fn nan_if_null<'de, D: serde::Deserializer<'de>>(d: D) -> Result<f64, D::Error> {
    Ok(Option::<f64>::deserialize(d)?.unwrap_or(f64::NAN))
}

impl GateResult {
    /// Judges a finished run against the gates.
    pub fn judge(summary: &RunSummary, gates: &GateSpec) -> GateResult {
        let mut failed = Vec::new();
        if !summary.finite {
            failed.push("non-finite values".to_string());
        }
        if summary.max_penetration_m > gates.max_penetration_m {
            failed.push(format!(
                "penetration {:.1} mm > {:.1} mm",
                summary.max_penetration_m * 1e3,
                gates.max_penetration_m * 1e3
            ));
        }
        let allowed = (gates.max_inside_fraction * summary.vertices as f64).floor() as usize;
        if summary.max_verts_inside > allowed {
            failed.push(format!(
                "{} vertices inside the body > {allowed}",
                summary.max_verts_inside
            ));
        }
        if summary.max_edge_stretch > gates.max_edge_stretch {
            failed.push(format!(
                "edge stretch {:.3} > {:.3}",
                summary.max_edge_stretch, gates.max_edge_stretch
            ));
        }
        if summary.max_self_intersections > gates.max_self_intersections {
            failed.push(format!(
                "{} self-intersections > {}",
                summary.max_self_intersections, gates.max_self_intersections
            ));
        }
        GateResult {
            finite: summary.finite,
            max_penetration_m: summary.max_penetration_m,
            max_verts_inside: summary.max_verts_inside,
            max_penetration_overlap_m: summary.max_penetration_overlap_m,
            max_verts_inside_overlap: summary.max_verts_inside_overlap,
            max_edge_stretch: summary.max_edge_stretch,
            max_self_intersections: summary.max_self_intersections,
            timed_out: false,
            passed: failed.is_empty(),
            failed,
        }
    }

    /// An attempt that did not finish: it ran out of time, could not be set up, or the solver
    /// gave a frame up (`finite` false when that was for a non-finite value).
    pub fn unfinished(reason: String, timed_out: bool, finite: bool) -> GateResult {
        GateResult {
            finite,
            max_penetration_m: f64::NAN,
            max_verts_inside: 0,
            max_penetration_overlap_m: f64::NAN,
            max_verts_inside_overlap: 0,
            max_edge_stretch: f64::NAN,
            max_self_intersections: 0,
            timed_out,
            passed: false,
            failed: vec![reason],
        }
    }
}

/// One attempt at a sequence.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Attempt {
    /// Solver settings used.
    pub solver: SolverParams,
    /// Gate results.
    pub gates: GateResult,
    /// Wall time, s.
    pub wall_s: f64,
}

/// One manifest line: everything about a sequence and where it is.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct ManifestRecord {
    /// What the plan says of the sequence: id, key, split, garment, motion, shape, material,
    /// friction and seed (flattened: one manifest line holds them as keys of its own).
    #[serde(flatten)]
    pub sequence: PlannedSequence,
    /// Output frames.
    pub frames: usize,
    /// Garment vertices.
    pub vertices: usize,
    /// `ok` (every gate passed) or `failed` (see `reason`; kept for inspection, not for
    /// training).
    pub status: Status,
    /// Why it failed (the last attempt's failed gates).
    pub reason: Option<String>,
    /// Every attempt, in order.
    pub attempts: Vec<Attempt>,
    /// Recording, relative to the dataset folder (none if no attempt finished).
    pub file: Option<String>,
    /// SHA-256 of the recording (hex).
    pub sha256: Option<String>,
    /// Size of the recording, bytes.
    pub bytes: u64,
    /// Software that made it.
    pub software: String,
    /// Wall time of all attempts, s.
    pub wall_s: f64,
}

/// One line of a synthesis log: `id status (frames, wall time): reason`.
impl std::fmt::Display for ManifestRecord {
    fn fmt(&self, f: &mut std::fmt::Formatter) -> std::fmt::Result {
        let (id, status, frames, wall) = (&self.sequence.id, self.status, self.frames, self.wall_s);
        write!(f, "{id} {status} ({frames} frames, {wall:.1} s)")?;
        match &self.reason {
            Some(reason) => write!(f, ": {reason}"),
            None => Ok(()),
        }
    }
}

impl ManifestRecord {
    /// The record of planned sequence `p` before any attempt: what the plan says of it,
    /// `failed` with no attempts, no recording and no frames yet.
    pub fn of_plan(p: &PlannedSequence, software: &str) -> Self {
        Self {
            sequence: p.clone(),
            frames: 0,
            vertices: 0,
            status: Status::Failed,
            reason: None,
            attempts: Vec::new(),
            file: None,
            sha256: None,
            bytes: 0,
            software: software.to_string(),
            wall_s: 0.0,
        }
    }

    /// Whether the sequence passed its gates.
    pub fn ok(&self) -> bool {
        self.status == Status::Ok
    }

    /// Checks that the id is a plain file name (not empty, no leading dot, no separator or
    /// NUL) and the recording (if any) is `sequences/<id>.mcap`, so a damaged or hostile
    /// manifest never points a reader (or a merge's copy, or a cache file named by the id)
    /// outside its folder: the one id check, for synthesis, merge, verify, tensors and
    /// evaluate.
    pub fn check_paths(&self) -> std::result::Result<(), RecordPathError> {
        let id = &self.sequence.id;
        let plain = !id.is_empty() && !id.starts_with('.') && !id.contains(['/', '\\', '\0']);
        if !plain {
            return Err(RecordPathError::Id(id.clone()));
        }
        match &self.file {
            Some(file) if *file != super::DatasetDir::sequence_file(id) => {
                Err(RecordPathError::File {
                    id: id.clone(),
                    file: file.clone(),
                })
            }
            _ => Ok(()),
        }
    }
}

/// Why [`ManifestRecord::check_paths`] refuses a record.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum RecordPathError {
    /// The id is not a plain file name.
    #[error("sequence id {0:?} is not a plain file name")]
    Id(String),
    /// The recording is not `sequences/<id>.mcap`.
    #[error("sequence {id}: recording {file:?} is not sequences/{id}.mcap")]
    File {
        /// The sequence.
        id: String,
        /// The recording it names.
        file: String,
    },
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn an_unfinished_attempt_reads_back_from_its_json() {
        let gates = GateResult::unfinished("ran out of time".into(), true, true);
        let line = serde_json::to_string(&gates).unwrap();
        assert!(line.contains("\"max_penetration_m\":null"), "{line}");
        let back: GateResult = serde_json::from_str(&line).unwrap();
        assert!(back.max_penetration_m.is_nan() && back.max_edge_stretch.is_nan());
        assert!(back.max_penetration_overlap_m.is_nan());
        assert_eq!((back.timed_out, back.passed), (true, false));
        assert_eq!(back.failed, gates.failed);
    }
}
