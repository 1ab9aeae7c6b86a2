//! What a scene configuration names, loaded: the body model, a motion (a built-in name with
//! optional parameters, an AMASS file or a BVH file) and a garment template (a library design or variant,
//! the built-in skirt, or an OBJ file). The command line, dataset synthesis and the surrogate's
//! tools load through here, so a name means the same thing in every command.

use std::path::Path;

use motions::{BodyModel, FramePose, Motion, MotionSource, POSE_DIM, ShapedBody};
use serde::Deserialize;

use crate::error::{Error, Result};
use crate::scene::BodyAttachment;

/// Body parameters of one pose (`body --params`): JSON with `betas`, `pose` (72 axis-angle
/// values, radians) and `transl` (metres), all optional.
#[derive(Debug, Default, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct BodyParams {
    /// Shape coefficients.
    #[serde(default)]
    pub betas: Vec<f64>,
    /// 72 axis-angle values: global_orient 3 + body_pose 69.
    #[serde(default)]
    pub pose: Option<Vec<f64>>,
    /// Root translation.
    #[serde(default)]
    pub transl: Option<Vec<f64>>,
}

impl BodyParams {
    /// Reads a parameters file and checks its lengths and numbers.
    pub fn load(path: &Path) -> Result<Self> {
        let text = files::read_to_string(path, files::limits::TEXT, "body parameters")?;
        let bad = |message: String| Error::Config {
            path: path.display().to_string(),
            message,
        };
        let params: Self = serde_json::from_str(&text)
            .map_err(|e| bad(format!("not a valid body parameters file: {e}")))?;
        for (key, values, expected) in [
            ("pose", &params.pose, POSE_DIM),
            ("transl", &params.transl, 3),
        ] {
            if let Some(v) = values.as_ref().filter(|v| v.len() != expected) {
                return Err(bad(format!(
                    "'{key}' has {} values, expected {expected}",
                    v.len()
                )));
            }
        }
        let all = params.betas.iter().chain(params.pose.iter().flatten());
        if all
            .chain(params.transl.iter().flatten())
            .any(|v| !v.is_finite())
        {
            return Err(bad("holds a non-finite number".into()));
        }
        Ok(params)
    }

    /// The pose and translation (the rest pose at the origin where absent).
    pub fn frame(&self) -> FramePose {
        let mut frame = FramePose {
            pose: [0.0; POSE_DIM],
            transl: [0.0; 3],
        };
        if let Some(pose) = &self.pose {
            frame.pose.copy_from_slice(pose);
        }
        if let Some(t) = &self.transl {
            frame.transl.copy_from_slice(t);
        }
        frame
    }
}

/// The body model in `path`, or the default body (CC0) without one.
pub fn body_model(path: Option<&Path>) -> Result<BodyModel> {
    match path {
        Some(p) => Ok(BodyModel::load(p)?),
        None => Ok(BodyModel::default_body()),
    }
}

/// A motion at 30 fps for `shaped`: a built-in name (with optional parameters), an AMASS
/// `.npz` file or a BVH file retargeted to SMPL, each file optionally a stretch
/// ([`motions::MotionSource`]).
pub fn motion(source: &str, model: &BodyModel, shaped: &ShapedBody) -> Result<Motion> {
    Ok(MotionSource::parse(source)?.load(model, shaped)?.motion)
}

/// A garment template and its body attachments: a library design (sewn on `model` once and
/// cached in `cache`, [`crate::templates::library_template`], `making` told the cache path
/// when it is made), the built-in skirt fitted to `model` and draped
/// ([`crate::scene::builtin_template`]), or an OBJ file with UVs (checked and repaired, no
/// attachments).
pub fn garment(
    source: &str,
    model: &BodyModel,
    cache: &Path,
    making: impl FnOnce(&Path),
) -> Result<(garments::Garment, Vec<BodyAttachment>)> {
    let fail = |problem: String| Error::Garment {
        garment: source.to_string(),
        problem,
    };
    if let Some(design) = garments::library::resolve(source) {
        let template = crate::templates::library_template(&design, model, cache, making)?;
        return Ok((template, Vec::new()));
    }
    let path = Path::new(source);
    if source.ends_with(".json") {
        // A sewing pattern (GarmentCode specification), sewn and cached as a library design.
        let pattern =
            garments::Pattern::read_seated(path).map_err(|e| fail(format!("pattern file: {e}")))?;
        let name = path
            .file_stem()
            .map_or_else(|| source.to_string(), |s| s.to_string_lossy().into_owned());
        let template = crate::templates::pattern_template(&name, &pattern, model, cache, making)?;
        return Ok((template, Vec::new()));
    }
    if source.ends_with(".obj") || path.exists() {
        let (raw, numbers) =
            garments::read_obj_numbered(path).map_err(|e| fail(format!("garment file: {e}")))?;
        let (template, _) = garments::repair_numbered(&raw, 1.0, Some(&numbers))
            .map_err(|e| fail(format!("garment file: {e}")))?;
        return Ok((template, Vec::new()));
    }
    if !garments::BUILTIN.contains(&source) {
        return Err(fail(format!(
            "unknown garment: not a library design ({}), a built-in ({}) or a file",
            garments::library::naming(),
            garments::BUILTIN.join(", ")
        )));
    }
    crate::scene::builtin_template(model, source, &garments::SkirtParams::default())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn names_resolve_or_are_refused_by_name() {
        let model = BodyModel::default_body();
        let shaped = model.shape(&[]).unwrap();
        let walk = motion("walk", &model, &shaped).unwrap();
        assert!(walk.len() > 10);
        let fast = motion("walk:speed=1.5", &model, &shaped).unwrap();
        assert_ne!(fast.frames[5], walk.frames[5]);
        assert!(motion("moonwalk", &model, &shaped).is_err());
        let cache = tempfile::tempdir().unwrap();
        let e = garment("cape", &model, cache.path(), |_| {}).unwrap_err();
        assert!(matches!(&e, Error::Garment { garment, .. } if garment == "cape"));
        assert!(
            e.to_string().starts_with("garment 'cape': unknown garment"),
            "{e}"
        );
        let e = garment("missing.obj", &model, cache.path(), |_| {}).unwrap_err();
        assert!(e.to_string().contains("garment file"), "{e}");
    }

    #[test]
    fn body_parameters_are_read_with_their_lengths_checked() {
        let dir = tempfile::tempdir().unwrap();
        let file = |name: &str, text: &str| {
            let path = dir.path().join(name);
            std::fs::write(&path, text).unwrap();
            path
        };
        let ok = file("ok.json", r#"{"betas": [1.0], "transl": [0.0, 1.0, 2.0]}"#);
        let params = BodyParams::load(&ok).unwrap();
        let frame = params.frame();
        assert_eq!(frame.transl, [0.0, 1.0, 2.0]);
        assert_eq!(frame.pose, [0.0; POSE_DIM]);
        for (name, text, expected) in [
            (
                "short.json",
                r#"{"pose": [0.0, 1.0]}"#,
                "'pose' has 2 values, expected 72",
            ),
            (
                "transl.json",
                r#"{"transl": [0.0]}"#,
                "'transl' has 1 values, expected 3",
            ),
            (
                "key.json",
                r#"{"shape": []}"#,
                "not a valid body parameters file",
            ),
        ] {
            let e = BodyParams::load(&file(name, text)).unwrap_err().to_string();
            assert!(e.contains(name) && e.contains(expected), "{e}");
        }
    }
}
