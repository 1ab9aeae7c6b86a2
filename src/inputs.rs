//! Turning flags into real objects: a garment (with a notice when its template is first made)
//! and body parameter files. Every error names the file or value at fault.

use std::path::Path;

use anyhow::{Context, Result, bail};
use motions::{BodyModel, POSE_DIM};
use serde::Deserialize;

/// Body parameters from a `--params` JSON file.
#[derive(Debug, Default, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct BodyParams {
    /// Shape coefficients.
    #[serde(default)]
    pub betas: Vec<f64>,
    /// 72 axis-angle values (radians).
    #[serde(default)]
    pub pose: Option<Vec<f64>>,
    /// Root translation (metres).
    #[serde(default)]
    pub transl: Option<Vec<f64>>,
}

impl BodyParams {
    /// Reads and checks a params file.
    pub fn load(path: &Path) -> Result<Self> {
        let text = files::read_to_string(path, files::limits::TEXT, "body parameters")?;
        let params: Self = serde_json::from_str(&text)
            .with_context(|| format!("{}: not a valid params file", path.display()))?;
        if let Some(pose) = &params.pose
            && pose.len() != POSE_DIM
        {
            bail!(
                "{}: 'pose' has {} values, expected 72 (global_orient 3 + body_pose 69)",
                path.display(),
                pose.len()
            );
        }
        if let Some(t) = &params.transl
            && t.len() != 3
        {
            bail!(
                "{}: 'transl' has {} values, expected 3",
                path.display(),
                t.len()
            );
        }
        let all = params
            .betas
            .iter()
            .chain(params.pose.iter().flatten())
            .chain(params.transl.iter().flatten());
        if all.clone().any(|v| !v.is_finite()) {
            bail!("{}: holds a non-finite number", path.display());
        }
        Ok(params)
    }
}

/// A garment template and its body attachments ([`sim::sources::garment`]), a library
/// design's made on first use and cached in the cache folder, with a notice when it is made.
pub fn garment(
    source: &str,
    model: &BodyModel,
) -> sim::Result<(garments::Garment, Vec<sim::scene::BodyAttachment>)> {
    let cache = sim::templates::cache_dir();
    sim::sources::garment(source, model, &cache, |path| {
        eprintln!(
            "making the template of '{source}' (first use; cached in {})",
            path.display()
        )
    })
}
