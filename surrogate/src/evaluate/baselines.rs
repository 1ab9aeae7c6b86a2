//! Predictions that need no learning, for every motion frame of a recorded sequence:
//! - `lbs`: the template skinned to the body with the skinning of the `lbs_residual` target
//!   (nearest-vertex weights, legs folded into the pelvis, smoothed): the baseline METRICS.md
//!   says every learned model must beat;
//! - `lbs_nearest`: plain nearest-body-vertex weights (skirts become trousers);
//! - `floor`: the ground truth encoded to the UV maps and read back (the best any UV model can
//!   do at that resolution and target);
//! - `rest`: the rest template carried rigidly by the root (the null model).

use motions::{BodyModel, ShapedBody};

use crate::data::Sequence;
use crate::error::Result;
use crate::geometry::{
    GeometryImage, RootRemoval, SMOOTHING_ROUNDS, Skinning, TargetKind, Targets,
};

/// The UV maps the `floor` baseline goes through.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct FloorMaps {
    /// Texels per side.
    pub resolution: usize,
    /// The target the maps hold.
    pub target: TargetKind,
    /// The canonical frame's root removal.
    pub root: RootRemoval,
}

impl Default for FloorMaps {
    /// The shipped model's maps (64 x 64, `lbs_residual`, heading removed): the floor of a
    /// run without a model.
    fn default() -> Self {
        Self {
            resolution: 64,
            target: TargetKind::LbsResidual,
            root: RootRemoval::Heading,
        }
    }
}

impl FloorMaps {
    /// The maps of the model scored beside it (its resolution, target and root removal), so
    /// the floor bounds that model; the default maps without one.
    pub fn of(model: Option<&crate::run::TrainedModel>) -> Self {
        model.map_or_else(Self::default, |t| Self {
            resolution: t.data.resolution,
            target: t.data.target,
            root: t.data.root,
        })
    }
}

/// Which baseline.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Baseline {
    /// The project's skinning.
    Lbs,
    /// Plain nearest-vertex skinning.
    LbsNearest,
    /// The UV round trip of the ground truth.
    Floor(FloorMaps),
    /// The rest template moved by the root.
    Rest,
}

/// The body shape of every frame, shaped once per run of equal shapes.
fn shapes(model: &BodyModel, seq: &Sequence, frames: &[usize]) -> Result<Vec<ShapedBody>> {
    let mut out: Vec<ShapedBody> = Vec::with_capacity(frames.len());
    for (i, &k) in frames.iter().enumerate() {
        let shaped = match out.last() {
            Some(s) if seq.betas[frames[i - 1]] == seq.betas[k] => s.clone(),
            _ => model.shape(&seq.betas[k])?,
        };
        out.push(shaped);
    }
    Ok(out)
}

/// The baseline's garment at each of `frames` (world, m).
pub fn predict(
    baseline: Baseline,
    model: &BodyModel,
    seq: &Sequence,
    frames: &[usize],
) -> Result<Vec<Vec<[f64; 3]>>> {
    let t = &seq.template;
    match baseline {
        Baseline::Lbs | Baseline::LbsNearest => {
            let skinning = if baseline == Baseline::Lbs {
                Skinning::new(model, &t.positions, &t.triangles, SMOOTHING_ROUNDS)?
            } else {
                Skinning::nearest(model, &t.positions)?
            };
            let shaped = shapes(model, seq, frames)?;
            Ok(frames
                .iter()
                .zip(&shaped)
                .map(|(&k, s)| skinning.pose(model, s, &seq.poses[k]))
                .collect())
        }
        Baseline::Rest => {
            let mut targets = Targets::new(
                model,
                &t.positions,
                &t.triangles,
                TargetKind::Displacement,
                RootRemoval::Full,
            )?;
            let zero = vec![[0.0; 3]; t.positions.len()];
            frames
                .iter()
                .map(|&k| targets.decode(model, seq.body(k), &zero))
                .collect()
        }
        Baseline::Floor(maps) => {
            let image = GeometryImage::of_template(t, maps.resolution)?;
            let mut targets =
                Targets::new(model, &t.positions, &t.triangles, maps.target, maps.root)?;
            frames
                .iter()
                .map(|&k| {
                    let base = targets.frame_base(model, seq.body(k))?;
                    let target = base.encode(&seq.garment[k]);
                    Ok(base.decode(&image.read(&image.encode(&target)?)?))
                })
                .collect()
        }
    }
}
