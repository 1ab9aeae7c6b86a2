//! Turning flags into real objects: the body model, a motion (built-in name or AMASS file), and
//! body parameter files. Every error names the file or value at fault.

use std::path::Path;

use anyhow::{Context, Result, bail};
use motions::library::MotionSpec;
use motions::{BodyModel, Motion, POSE_DIM, ShapedBody};
use serde::Deserialize;

/// The body model named by `--model`, or the default body.
pub fn body_model(path: Option<&Path>) -> Result<BodyModel> {
    match path {
        Some(p) => Ok(BodyModel::load(p)?),
        None => Ok(BodyModel::default_body()),
    }
}

/// A motion at 30 fps: a built-in name (with optional parameters) generated for `shaped`, or an
/// AMASS `.npz` file resampled by time.
pub fn motion(source: &str, model: &BodyModel, shaped: &ShapedBody) -> Result<Motion> {
    let path = Path::new(source);
    if source.ends_with(".npz") || path.exists() {
        let raw = motions::amass::load(path, shaped.joints[0])?;
        return raw
            .resample(30.0)
            .with_context(|| format!("resampling {source} to 30 fps"));
    }
    Ok(MotionSpec::parse(source)?.generate(model, shaped)?)
}

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

/// A garment template and its body attachments: a library design (sewn on `model` once and
/// cached, see [`library_template`]), the built-in skirt fitted to `model` and draped
/// ([`sim::scene::builtin_template`]), or an OBJ file with UVs (checked and repaired, no
/// attachments).
pub fn garment(
    source: &str,
    model: &BodyModel,
) -> Result<(garments::Garment, Vec<sim::scene::BodyAttachment>)> {
    if let Some(design) = garments::library::resolve(source) {
        return Ok((library_template(&design, model)?, Vec::new()));
    }
    let path = Path::new(source);
    if source.ends_with(".obj") || path.exists() {
        let (raw, numbers) = garments::read_obj_numbered(path)?;
        let (template, _) = garments::repair_numbered(&raw, 1.0, Some(&numbers))
            .map_err(|e| anyhow::anyhow!("garment file {source}: {e}"))?;
        return Ok((template, Vec::new()));
    }
    if !garments::BUILTIN.contains(&source) {
        bail!(
            "unknown garment '{source}': not a library design ({}), a built-in ({}) or a file",
            garments::library::naming(),
            garments::BUILTIN.join(", ")
        );
    }
    sim::scene::builtin_template(model, source, &garments::SkirtParams::default())
        .with_context(|| format!("preparing built-in garment '{source}'"))
}

/// A library design's (or a variant's) template on `model`, made on first use and cached in
/// the cache folder ([`sim::templates::library_template`]).
pub fn library_template(
    design: &garments::library::NamedDesign,
    model: &BodyModel,
) -> Result<garments::Garment> {
    let cache = sim::templates::cache_dir();
    Ok(sim::templates::library_template(
        design,
        model,
        &cache,
        |path| {
            eprintln!(
                "making the template of '{}' (first use; cached in {})",
                design.name,
                path.display()
            )
        },
    )?)
}
