//! The two training targets of a frame and their decoding: per garment vertex, in the frame's
//! canonical frame, `displacement` (cloth minus the rest template, the paper's) or
//! `lbs_residual` (cloth minus the template skinned to the current body). Both decode to the
//! same mesh: `world(base + target)`.

use motions::{BodyModel, FramePose, ShapedBody};
use serde::{Deserialize, Serialize};

use super::canonical::{Canonical, RootRemoval};
use super::skinning::{SMOOTHING_ROUNDS, Skinning};
use crate::error::Result;

/// What a model predicts per vertex.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum TargetKind {
    /// Canonical cloth minus the rest template (the paper's displacement map).
    #[default]
    Displacement,
    /// Canonical cloth minus the template skinned to the current body.
    LbsResidual,
}

impl TargetKind {
    /// The name used by flags and files.
    pub fn name(self) -> &'static str {
        match self {
            Self::Displacement => "displacement",
            Self::LbsResidual => "lbs_residual",
        }
    }

    /// Parses a flag value.
    pub fn parse(text: &str) -> Option<Self> {
        match text {
            "displacement" => Some(Self::Displacement),
            "lbs_residual" => Some(Self::LbsResidual),
            _ => None,
        }
    }
}

/// One frame's body: pose, translation and shape, as a recording holds them.
#[derive(Debug, Clone, Copy)]
pub struct FrameBody<'a> {
    /// The pose and root translation.
    pub pose: &'a FramePose,
    /// The shape of the frame.
    pub betas: &'a [f64],
}

/// Targets of one template on one body model.
#[derive(Debug, Clone)]
pub struct Targets {
    kind: TargetKind,
    removal: RootRemoval,
    template: Vec<[f64; 3]>,
    skinning: Option<Skinning>,
    rest_pelvis: [f64; 3],
    /// The last shape asked for, reused while frames keep it.
    shaped: Option<ShapedBody>,
}

/// What one frame's targets are measured from: its canonical map and the base positions
/// (canonical) a target is added to, the template skinned to the frame's body for
/// `lbs_residual` and the rest template for `displacement`. Made once per frame, it decodes
/// any number of targets (the sampler's guidance decodes one per step).
#[derive(Debug, Clone)]
pub struct FrameBase {
    canonical: Canonical,
    base: Vec<[f64; 3]>,
}

impl FrameBase {
    /// The frame's canonical map.
    pub fn canonical(&self) -> &Canonical {
        &self.canonical
    }

    /// The base positions (canonical, m): the skinned template or the rest template.
    pub fn base(&self) -> &[[f64; 3]] {
        &self.base
    }

    /// The cloth (world, m) a per-vertex target stands for.
    pub fn decode(&self, target: &[[f64; 3]]) -> Vec<[f64; 3]> {
        target
            .iter()
            .zip(&self.base)
            .map(|(d, b)| {
                self.canonical
                    .to_world([b[0] + d[0], b[1] + d[1], b[2] + d[2]])
            })
            .collect()
    }

    /// The per-vertex target of cloth at `garment` (world, m).
    pub fn encode(&self, garment: &[[f64; 3]]) -> Vec<[f64; 3]> {
        garment
            .iter()
            .zip(&self.base)
            .map(|(x, b)| {
                let c = self.canonical.to_canonical(*x);
                [c[0] - b[0], c[1] - b[1], c[2] - b[2]]
            })
            .collect()
    }

    /// A world gradient with respect to a decoded vertex as the gradient with respect to its
    /// target (decoding is a rigid map of base + target).
    pub fn gradient_to_target(&self, world: [f64; 3]) -> [f64; 3] {
        self.canonical.direction_to_canonical(world)
    }
}

impl Targets {
    /// Targets of a template (rest positions on the template body, `triangles` over them)
    /// on `model`.
    pub fn new(
        model: &BodyModel,
        template: &[[f64; 3]],
        triangles: &[[u32; 3]],
        kind: TargetKind,
        removal: RootRemoval,
    ) -> Result<Self> {
        let skinning = match kind {
            TargetKind::Displacement => None,
            TargetKind::LbsResidual => {
                Some(Skinning::new(model, template, triangles, SMOOTHING_ROUNDS)?)
            }
        };
        Ok(Self {
            kind,
            removal,
            template: template.to_vec(),
            skinning,
            rest_pelvis: model.shape(&[])?.joints[0],
            shaped: None,
        })
    }

    /// The target kind.
    pub fn kind(&self) -> TargetKind {
        self.kind
    }

    /// The base of a frame (see [`FrameBase`]).
    pub fn frame_base(&mut self, model: &BodyModel, body: FrameBody) -> Result<FrameBase> {
        if self.shaped.as_ref().is_none_or(|s| s.betas != body.betas) {
            self.shaped = Some(model.shape(body.betas)?);
        }
        let shaped = self.shaped.as_ref().expect("set above");
        let j0 = shaped.joints[0];
        let t = body.pose.transl;
        let pelvis = [j0[0] + t[0], j0[1] + t[1], j0[2] + t[2]];
        let p = &body.pose.pose;
        let canonical = Canonical::new(self.removal, [p[0], p[1], p[2]], pelvis, self.rest_pelvis);
        let base = match &self.skinning {
            Some(skinning) => skinning
                .pose(model, shaped, body.pose)
                .into_iter()
                .map(|q| canonical.to_canonical(q))
                .collect(),
            None => self.template.clone(),
        };
        Ok(FrameBase { canonical, base })
    }

    /// The body inputs of a frame (body `now`, previous frame's body `before`), per vertex
    /// in the frame's canonical frame, m: the template skinned to the body, and its change
    /// since the previous frame (both skinned templates in `now`'s canonical frame, so the
    /// root's own motion is in it), the first as `now`'s [`FrameBase`]. Only an
    /// `lbs_residual` target has the skinning.
    pub fn body_inputs(
        &mut self,
        model: &BodyModel,
        now: FrameBody,
        before: FrameBody,
    ) -> Result<(FrameBase, Vec<[f64; 3]>)> {
        if self.skinning.is_none() {
            return Err(crate::error::Error::NeedsLbsResidual {
                what: "body inputs",
            });
        }
        let previous = self.frame_base(model, before)?;
        let previous_world = previous.decode(&vec![[0.0; 3]; self.template.len()]);
        let current = self.frame_base(model, now)?;
        let change = current
            .encode(&previous_world)
            .into_iter()
            .map(|d| [-d[0], -d[1], -d[2]])
            .collect();
        Ok((current, change))
    }

    /// The per-vertex target of a frame whose cloth is at `garment` (world, m).
    pub fn encode(
        &mut self,
        model: &BodyModel,
        body: FrameBody,
        garment: &[[f64; 3]],
    ) -> Result<Vec<[f64; 3]>> {
        Ok(self.frame_base(model, body)?.encode(garment))
    }

    /// The cloth (world, m) a per-vertex target stands for.
    pub fn decode(
        &mut self,
        model: &BodyModel,
        body: FrameBody,
        target: &[[f64; 3]],
    ) -> Result<Vec<[f64; 3]>> {
        Ok(self.frame_base(model, body)?.decode(target))
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use motions::canonical_a_pose;

    #[test]
    fn both_targets_decode_to_the_cloth_they_encode() {
        let model = BodyModel::default_body();
        let template: Vec<[f64; 3]> = model.template().iter().step_by(211).copied().collect();
        let mut pose = canonical_a_pose();
        pose[1] = 0.8; // turned about +y
        pose[3 * 18] = 0.5; // left elbow
        let frame = FramePose {
            pose,
            transl: [0.3, 0.05, -1.0],
        };
        let betas = [0.5, -1.0];
        let cloth: Vec<[f64; 3]> = template
            .iter()
            .map(|p| [p[0] + 0.3, p[1] + 0.02, p[2] - 0.9])
            .collect();
        for kind in [TargetKind::Displacement, TargetKind::LbsResidual] {
            let mut targets =
                Targets::new(&model, &template, &[], kind, RootRemoval::Heading).unwrap();
            let body = FrameBody {
                pose: &frame,
                betas: &betas,
            };
            let t = targets.encode(&model, body, &cloth).unwrap();
            let back = targets.decode(&model, body, &t).unwrap();
            for (a, b) in back.iter().zip(&cloth) {
                let d = (0..3).map(|k| (a[k] - b[k]).abs()).fold(0.0, f64::max);
                assert!(d < 1e-12, "{kind:?}: {a:?} vs {b:?}");
            }
        }
    }
}
