//! Scoring predictions of recorded sequences with the metric suite (`sim::metrics`, exactly
//! METRICS.md) plus what the paper lacks: jitter (temporal smoothness against the
//! simulation's), `stretch_p99` and `inside_percent` (plausibility, since each cheap baseline
//! fails one of them). The methods: the model with and without guidance, and the baselines of
//! `baselines.rs`.
//!
//! Protocol: the motion frames of a sequence (after its blend-in and settle frames, the frames
//! a model learns from); every 5th of them scored and averaged, then sequences averaged;
//! jitter over all motion frames.

pub mod baselines;
pub mod family;
pub mod paired;
mod protocol;
pub mod report;
pub mod tables;

pub use protocol::{Evaluation, describe_model, document, fingerprint, select};

use serde::{Deserialize, Serialize};
use sim::metrics::{BodySurface, FRAME_STRIDE, Scorer, Scores, jitter};
use sim::obstacles::{MeshSurface, Penetration, split_penetration};

use motions::BodyModel;

use crate::data::Sequence;
use crate::error::{Error, Result};
use crate::predict::clearances;

/// The methods a report compares, in its order.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, PartialOrd, Ord, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum Method {
    /// The model with intersection guidance.
    Model,
    /// The model without guidance.
    ModelNoGuidance,
    /// The template skinned with the project's skinning.
    Lbs,
    /// Plain nearest-vertex skinning.
    LbsNearest,
    /// The ground truth's UV round trip.
    Floor,
    /// The rest template carried by the root.
    Rest,
    /// The engine again with a nudged setting (`dataset spread`): the ground truth's spread.
    Resimulated,
}

impl Method {
    /// Every method, in report order.
    pub const ALL: [Method; 7] = [
        Method::Model,
        Method::ModelNoGuidance,
        Method::Lbs,
        Method::LbsNearest,
        Method::Floor,
        Method::Rest,
        Method::Resimulated,
    ];

    /// The name used by flags and files.
    pub fn name(self) -> &'static str {
        match self {
            Method::Model => "model",
            Method::ModelNoGuidance => "model_no_guidance",
            Method::Lbs => "lbs",
            Method::LbsNearest => "lbs_nearest",
            Method::Floor => "floor",
            Method::Rest => "rest",
            Method::Resimulated => "resimulated",
        }
    }

    /// Parses a name.
    pub fn parse(name: &str) -> Option<Method> {
        Method::ALL.into_iter().find(|m| m.name() == name)
    }
}

/// The figures of one method on one sequence, or their mean over sequences.
#[derive(Debug, Clone, Copy, Default, PartialEq, Serialize, Deserialize)]
pub struct MethodScores {
    /// The paper's metrics (units in [`units`]).
    #[serde(flatten)]
    pub scores: Scores,
    /// Mean |second difference| of vertex positions over the motion frames, cm.
    pub jitter: f64,
    /// 99th percentile of edge length over rest length, over the scored frames.
    pub stretch_p99: f64,
    /// Vertices inside the body (exact inside test), %, mean over the scored frames.
    pub inside_percent: f64,
    /// The part of `inside_percent` where the body overlaps itself
    /// (`sim::obstacles::split_penetration`), %.
    #[serde(default)]
    pub inside_overlap_percent: f64,
    /// Deepest vertex inside the body away from its overlaps, over the scored frames (and
    /// sequences), m: the engine's gated figure.
    #[serde(default)]
    pub max_penetration_m: f64,
    /// Deepest vertex inside the body where it overlaps itself, m.
    #[serde(default)]
    pub max_penetration_overlap_m: f64,
    /// Predicted frames per second, preparation excluded.
    pub fps: f64,
    /// Frames scored.
    pub frames_scored: usize,
    /// Frames predicted (every motion frame), the count `fps` is measured over.
    #[serde(default)]
    pub frames_predicted: usize,
    /// Sequences averaged (1 for a sequence's own row).
    pub sequences: usize,
}

/// The units of a [`MethodScores`]'s keys besides the paper's metrics ([`Scores::UNITS`]).
const MORE_UNITS: [(&str, &str); 10] = [
    ("jitter", "cm (mean second difference over frames)"),
    ("stretch_p99", "1 (edge length over rest length)"),
    (
        "inside_percent",
        "% of garment vertices inside the body (exact inside test)",
    ),
    (
        "inside_overlap_percent",
        "% of garment vertices inside the body where it overlaps itself",
    ),
    ("max_penetration_m", "m (outside the body's own overlaps)"),
    (
        "max_penetration_overlap_m",
        "m (where the body overlaps itself)",
    ),
    ("fps", "frames/s"),
    ("sequences", "count"),
    ("frames_scored", "count"),
    ("frames_predicted", "count"),
];

/// Every key of a [`MethodScores`] with its unit, as a JSON object.
pub fn units() -> serde_json::Map<String, serde_json::Value> {
    Scores::UNITS
        .iter()
        .chain(&MORE_UNITS)
        .map(|(k, u)| (k.to_string(), u.to_string().into()))
        .collect()
}

impl MethodScores {
    /// The mean of sequences' rows (fps: frames predicted over their summed time; counts
    /// summed; the deepest penetrations their largest).
    pub fn mean(rows: &[MethodScores]) -> MethodScores {
        let n = rows.len().max(1) as f64;
        let scores: Vec<Scores> = rows.iter().map(|r| r.scores).collect();
        let avg = |f: fn(&MethodScores) -> f64| rows.iter().map(f).sum::<f64>() / n;
        let most = |f: fn(&MethodScores) -> f64| rows.iter().map(f).fold(0.0, f64::max);
        let frames: f64 = rows.iter().map(|r| r.frames_predicted as f64).sum();
        let time: f64 = rows
            .iter()
            .map(|r| r.frames_predicted as f64 / r.fps.max(1e-12))
            .sum();
        MethodScores {
            scores: Scores::mean(&scores),
            jitter: avg(|r| r.jitter),
            stretch_p99: avg(|r| r.stretch_p99),
            inside_percent: avg(|r| r.inside_percent),
            inside_overlap_percent: avg(|r| r.inside_overlap_percent),
            max_penetration_m: most(|r| r.max_penetration_m),
            max_penetration_overlap_m: most(|r| r.max_penetration_overlap_m),
            fps: if time > 0.0 { frames / time } else { 0.0 },
            frames_scored: rows.iter().map(|r| r.frames_scored).sum(),
            frames_predicted: rows.iter().map(|r| r.frames_predicted).sum(),
            sequences: rows.iter().map(|r| r.sequences).sum(),
        }
    }
}

/// What predictions of one sequence are scored against: its motion frames, the scored ones'
/// bodies and the template's edges.
pub struct Truth<'a> {
    seq: &'a Sequence,
    /// The motion frames (recording indices).
    frames: Vec<usize>,
    /// Every 5th motion frame, as offsets into `frames`.
    scored: Vec<usize>,
    bodies: Vec<Vec<[f64; 3]>>,
    surfaces: Vec<MeshSurface>,
    faces: &'a [[u32; 3]],
    scorer: Scorer,
    /// Edges with their rest lengths.
    edges: Vec<(u32, u32, f64)>,
}

/// The undirected edges of triangles, each once.
fn edges(triangles: &[[u32; 3]]) -> Vec<(u32, u32)> {
    let mut e: Vec<(u32, u32)> = triangles
        .iter()
        .flat_map(|t| (0..3).map(move |k| (t[k].min(t[(k + 1) % 3]), t[k].max(t[(k + 1) % 3]))))
        .collect();
    e.sort_unstable();
    e.dedup();
    e
}

fn distance(a: [f64; 3], b: [f64; 3]) -> f64 {
    ((a[0] - b[0]).powi(2) + (a[1] - b[1]).powi(2) + (a[2] - b[2]).powi(2)).sqrt()
}

/// The points inside `body` (exact inside test), split by whether it overlaps itself there.
fn split_inside(body: &MeshSurface, points: &[[f64; 3]]) -> Penetration {
    let distances: Vec<f64> = clearances(body, points, 0.0)
        .iter()
        .map(|c| c.map_or(f64::INFINITY, |c| c.distance))
        .collect();
    let points: Vec<sim::Vec3> = points.iter().map(|&p| sim::Vec3::from(p)).collect();
    split_penetration(body, &points, &distances)
}

impl<'a> Truth<'a> {
    /// The truth of a recorded sequence on `model` (the body model it was simulated with).
    pub fn new(seq: &'a Sequence, model: &'a BodyModel, seed: u64) -> Result<Self> {
        let frames: Vec<usize> = (seq.first_motion_frame()..seq.len()).collect();
        if frames.is_empty() {
            return Err(Error::NothingToScore {
                garment: seq.meta.garment.clone(),
                motion: seq.meta.motion.clone(),
            });
        }
        let scored: Vec<usize> = (0..frames.len()).step_by(FRAME_STRIDE).collect();
        let mut bodies = Vec::with_capacity(scored.len());
        let mut surfaces = Vec::with_capacity(scored.len());
        for &i in &scored {
            let k = frames[i];
            let shaped = model.shape(&seq.betas[k])?;
            let body = model.pose(&shaped, &seq.poses[k])?.vertices;
            let v: Vec<sim::Vec3> = body.iter().map(|p| sim::Vec3::from(*p)).collect();
            surfaces.push(MeshSurface::new("body", &v, model.faces())?);
            bodies.push(body);
        }
        let rest = &seq.template.positions;
        let edges = edges(&seq.template.triangles)
            .into_iter()
            .map(|(a, b)| {
                (
                    a,
                    b,
                    distance(rest[a as usize], rest[b as usize]).max(1e-12),
                )
            })
            .collect();
        Ok(Self {
            seq,
            frames,
            scored,
            bodies,
            surfaces,
            faces: model.faces(),
            scorer: Scorer::new(rest, &seq.template.triangles, seed),
            edges,
        })
    }

    /// The motion frames (recording indices) a prediction must cover, in order.
    pub fn frames(&self) -> &[usize] {
        &self.frames
    }

    /// The ground truth at the motion frames.
    pub fn ground_truth(&self) -> Vec<Vec<[f64; 3]>> {
        self.frames
            .iter()
            .map(|&k| self.seq.garment[k].clone())
            .collect()
    }

    /// Jitter, `stretch_p99` and `inside_percent` of the simulation itself, the reference the
    /// methods' are read against.
    pub fn simulation(&self) -> MethodScores {
        self.score(&self.ground_truth(), 0.0)
    }

    /// Scores a prediction of every motion frame (`predicted[i]` for `frames()[i]`), made at
    /// `fps` frames per second.
    pub fn score(&self, predicted: &[Vec<[f64; 3]>], fps: f64) -> MethodScores {
        let mut per_frame = Vec::with_capacity(self.scored.len());
        let mut ratios = Vec::new();
        let (mut inside, mut inside_overlap) = (0.0, 0.0);
        let mut deepest = Penetration::default();
        for (j, &i) in self.scored.iter().enumerate() {
            let k = self.frames[i];
            let pred = &predicted[i];
            let body = BodySurface {
                vertices: &self.bodies[j],
                triangles: self.faces,
            };
            per_frame.push(
                self.scorer
                    .frame(pred, &self.seq.garment[k], Some(&body), k),
            );
            ratios.extend(
                self.edges
                    .iter()
                    .map(|&(a, b, r)| distance(pred[a as usize], pred[b as usize]) / r),
            );
            let split = split_inside(&self.surfaces[j], pred);
            let percent = 100.0 / pred.len().max(1) as f64;
            inside += percent * (split.inside + split.overlap_inside) as f64;
            inside_overlap += percent * split.overlap_inside as f64;
            deepest = deepest.max(split);
        }
        let frames = self.scored.len().max(1) as f64;
        ratios.sort_by(f64::total_cmp);
        let p99 = ratios
            .get(((ratios.len() as f64 * 0.99) as usize).min(ratios.len().saturating_sub(1)))
            .copied()
            .unwrap_or(f64::NAN);
        MethodScores {
            scores: Scores::mean(&per_frame),
            jitter: jitter(predicted),
            stretch_p99: p99,
            inside_percent: inside / frames,
            inside_overlap_percent: inside_overlap / frames,
            max_penetration_m: deepest.depth_m,
            max_penetration_overlap_m: deepest.overlap_depth_m,
            fps,
            frames_scored: self.scored.len(),
            frames_predicted: predicted.len(),
            sequences: 1,
        }
    }
}
