//! A scene configuration as plain data: everything that defines a garment sequence (garment,
//! motion, body shape, material, friction, frames, blend-in, solver settings, what the
//! recording carries), saved and loaded as TOML, checked by one [`SceneConfig::validate`] that
//! names the key and the bad value.
//!
//! A configuration is resolved in layers: the defaults, then a file (`--config`) or the
//! configuration a recording carries (`--config-from`), then command-line flags. Every
//! recording stores the resolved configuration in its metadata, so any sequence can be
//! simulated again from its recording alone.

use std::path::Path;

use serde::{Deserialize, Serialize};

use crate::error::{Error, Result};
use crate::params::{Material, SolverParams};

/// Everything that defines a garment sequence. The TOML keys are the field names; `material`,
/// `solver` and `record` are tables (docs/FORMATS.md lists every key with its unit).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct SceneConfig {
    /// Garment: a library design, a built-in (`skirt`, `default`) or a template OBJ file.
    pub garment: String,
    /// Motion: a built-in name (with optional `:speed=..,amplitude=..,duration=..`) or an AMASS
    /// `.npz` file.
    pub motion: String,
    /// SMPL-format `.npz` body model file; the licence-free default body when absent.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub model: Option<String>,
    /// Shape coefficients (missing ones are 0).
    pub betas: Vec<f64>,
    /// Cloth-body friction coefficient.
    pub friction: f64,
    /// Output frames to simulate, blend-in and settle included; the whole motion when absent.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub frames: Option<usize>,
    /// Frames blending from the canonical pose and shape into the motion's first frame.
    pub blend_frames: usize,
    /// Frames holding the first frame after the blend.
    pub settle_frames: usize,
    /// The sequence's seed (dataset sequences), recorded in the metadata; the engine draws no
    /// random numbers.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub seed: Option<u64>,
    /// Cloth material.
    pub material: Material,
    /// Solver settings.
    pub solver: SolverParams,
    /// What the recording carries besides the garment.
    pub record: RecordConfig,
}

/// What a recording carries besides the garment, its template, the body pose and statistics.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct RecordConfig {
    /// The body vertices of every frame (large).
    pub body_vertices: bool,
    /// A `foxglove.SceneUpdate` channel for Foxglove's 3D panel (large).
    pub foxglove: bool,
}

/// The solver settings of garment scenes: 4 substeps x 16 iterations with cloth-cloth contact.
pub fn garment_solver() -> SolverParams {
    SolverParams {
        substeps: 4,
        max_iterations: 16,
        self_contact: true,
        ..SolverParams::default()
    }
}

impl Default for SceneConfig {
    fn default() -> Self {
        Self {
            garment: "default".into(),
            motion: "walk".into(),
            model: None,
            betas: Vec::new(),
            friction: 0.3,
            frames: None,
            blend_frames: 30,
            settle_frames: 30,
            seed: None,
            material: Material::default(),
            solver: garment_solver(),
            record: RecordConfig::default(),
        }
    }
}

pub use motions::MAX_PREFIX_FRAMES;

/// The most shape coefficients a scene may give (SMPL-X has 300).
pub const MAX_BETAS: usize = 300;
/// The largest shape coefficient, in standard deviations of the shape space.
pub const MAX_BETA: f64 = 10.0;

/// The most output frames a scene may ask for: the longest motion and both prefixes.
pub const MAX_FRAMES: usize = motions::MAX_MOTION_FRAMES + 2 * MAX_PREFIX_FRAMES;

/// A scene configuration whose values are checked ([`SceneConfig::validated`]): the one kind
/// [`crate::scene::Scene::new`] takes, so no scene is built from unchecked values and no later
/// stage checks them again. Read it through `Deref`; to change it, take it apart
/// ([`Self::into_inner`]) and validate again.
#[derive(Debug, Clone, PartialEq)]
pub struct ValidSceneConfig(SceneConfig);

impl ValidSceneConfig {
    /// The configuration, to change (and validate again).
    pub fn into_inner(self) -> SceneConfig {
        self.0
    }
}

impl std::ops::Deref for ValidSceneConfig {
    type Target = SceneConfig;

    fn deref(&self) -> &SceneConfig {
        &self.0
    }
}

impl SceneConfig {
    /// Checks every value, naming the key and the bad value in the error.
    pub fn validate(&self) -> Result<()> {
        if self.garment.trim().is_empty() {
            return Err(Error::value("garment", "\"\"", "must name a garment"));
        }
        if self.motion.trim().is_empty() {
            return Err(Error::value("motion", "\"\"", "must name a motion"));
        }
        if !(self.friction.is_finite() && self.friction >= 0.0) {
            return Err(Error::value(
                "friction",
                self.friction,
                "must be finite and >= 0",
            ));
        }
        if self.betas.len() > MAX_BETAS {
            return Err(Error::value(
                "betas",
                format!("{} values", self.betas.len()),
                &format!("must have at most {MAX_BETAS}"),
            ));
        }
        if let Some(i) = self
            .betas
            .iter()
            .position(|b| b.is_nan() || b.abs() > MAX_BETA)
        {
            return Err(Error::value(
                &format!("betas[{i}]"),
                self.betas[i],
                &format!("must be within [-{MAX_BETA}, {MAX_BETA}]"),
            ));
        }
        match self.frames {
            Some(0) => return Err(Error::value("frames", 0, "must be at least 1")),
            Some(n) if n > MAX_FRAMES => {
                return Err(Error::value(
                    "frames",
                    n,
                    &format!("must be at most {MAX_FRAMES} (a motion and both prefixes)"),
                ));
            }
            _ => {}
        }
        for (key, value) in [
            ("blend_frames", self.blend_frames),
            ("settle_frames", self.settle_frames),
        ] {
            if value > MAX_PREFIX_FRAMES {
                return Err(Error::value(
                    key,
                    value,
                    &format!("must be at most {MAX_PREFIX_FRAMES} (an hour at 30 fps)"),
                ));
            }
        }
        self.material.validate()?;
        self.solver.validate()
    }

    /// This configuration, its values checked ([`Self::validate`]): the one form a scene is
    /// built from.
    pub fn validated(self) -> Result<ValidSceneConfig> {
        self.validate()?;
        Ok(ValidSceneConfig(self))
    }

    /// The configuration as TOML (what `--print-config` prints and `--config` reads back).
    pub fn to_toml(&self) -> String {
        toml::to_string(self).expect("a scene configuration serializes as TOML")
    }

    /// Reads a configuration file over the defaults: keys the file leaves out keep their
    /// default values; an unknown key or a value of the wrong type is an error naming the
    /// file and the key. The result is not validated (flags may still change it).
    pub fn load(path: &Path) -> Result<Self> {
        let name = path.display().to_string();
        let text = files::read_to_string(path, files::limits::TEXT, "scene configuration")?;
        Self::from_toml(&text, &name)
    }

    /// Parses a configuration over the defaults; `source` names it in errors.
    pub fn from_toml(text: &str, source: &str) -> Result<Self> {
        toml_over_defaults(text, &Self::default(), &Self::every_key()).map_err(|message| {
            Error::Config {
                path: source.to_string(),
                message,
            }
        })
    }

    /// A configuration with every optional key present, to list the known keys.
    fn every_key() -> Self {
        Self {
            model: Some(String::new()),
            frames: Some(0),
            seed: Some(0),
            ..Self::default()
        }
    }
}

/// Parses TOML `text` laid over `defaults`: keys the text leaves out keep their default
/// values; a key that `every_key` (the type with every optional key present) lacks is an error
/// naming its dotted path, as is a value of the wrong type. Shared by every configuration
/// file of the project (scenes here, the surrogate's model and training).
pub fn toml_over_defaults<T: Serialize + serde::de::DeserializeOwned>(
    text: &str,
    defaults: &T,
    every_key: &T,
) -> std::result::Result<T, String> {
    let file: toml::Table = toml::from_str(text).map_err(|e| e.to_string())?;
    let known = toml::Table::try_from(every_key).map_err(|e| e.to_string())?;
    if let Some(key) = unknown_key(&file, &known, "") {
        return Err(format!(
            "unknown key '{key}' (print the known keys with `--print-config`)"
        ));
    }
    let mut merged = toml::Table::try_from(defaults).map_err(|e| e.to_string())?;
    merge(&mut merged, file);
    toml::Value::Table(merged)
        .try_into()
        .map_err(|e: toml::de::Error| e.message().to_string())
}

/// The first key of `file` (dotted path) that `known` does not have; arrays and values are
/// not looked into (the deserializer checks their types).
fn unknown_key(file: &toml::Table, known: &toml::Table, prefix: &str) -> Option<String> {
    for (key, value) in file {
        let path = if prefix.is_empty() {
            key.clone()
        } else {
            format!("{prefix}.{key}")
        };
        match (known.get(key), value) {
            (None, _) => return Some(path),
            (Some(toml::Value::Table(k)), toml::Value::Table(v)) => {
                if let Some(bad) = unknown_key(v, k, &path) {
                    return Some(bad);
                }
            }
            _ => {}
        }
    }
    None
}

/// Lays `over` onto `base`, table by table.
fn merge(base: &mut toml::Table, over: toml::Table) {
    for (key, value) in over {
        match (base.get_mut(&key), value) {
            (Some(toml::Value::Table(b)), toml::Value::Table(o)) => merge(b, o),
            (_, value) => {
                base.insert(key, value);
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_defaults_round_trip_through_toml() {
        let config = SceneConfig {
            betas: vec![0.1, -2.5e-3],
            frames: Some(40),
            seed: Some(7),
            ..SceneConfig::default()
        };
        config.validate().unwrap();
        let back = SceneConfig::from_toml(&config.to_toml(), "test").unwrap();
        assert_eq!(back, config);
    }

    #[test]
    fn a_partial_file_keeps_the_other_defaults() {
        let config =
            SceneConfig::from_toml("motion = \"run\"\n[solver]\nsubsteps = 8\n", "t").unwrap();
        assert_eq!(config.motion, "run");
        assert_eq!(config.solver.substeps, 8);
        assert_eq!(
            config.solver.max_iterations, 16,
            "the garment default stays"
        );
        assert!(config.solver.self_contact);
        assert_eq!(config.garment, "default");
    }

    #[test]
    fn unknown_keys_and_bad_values_are_named() {
        let e = SceneConfig::from_toml("[solver]\nsubstep = 8\n", "s.toml").unwrap_err();
        let message = e.to_string();
        assert!(message.contains("s.toml"), "{message}");
        assert!(message.contains("solver.substep"), "{message}");
        let e = SceneConfig::from_toml("frames = \"ten\"\n", "s.toml").unwrap_err();
        assert!(e.to_string().contains("s.toml"), "{e}");
        let config = SceneConfig::from_toml("[material]\nk_s_n_per_m = -1.0\n", "s").unwrap();
        let message = config.validate().unwrap_err().to_string();
        assert!(message.contains("material.k_s_n_per_m = -1"), "{message}");
        let config = SceneConfig::from_toml("friction = nan\n", "s").unwrap();
        let message = config.validate().unwrap_err().to_string();
        assert!(message.starts_with("friction = NaN"), "{message}");
        let config = SceneConfig::from_toml("settle_frames = 4000000000\n", "s").unwrap();
        let message = config.validate().unwrap_err().to_string();
        assert!(message.contains("settle_frames"), "{message}");
        let text = "[solver]\nmax_penetration_jump = -0.01\n";
        let config = SceneConfig::from_toml(text, "s").unwrap();
        let message = config.validate().unwrap_err().to_string();
        assert!(message.contains("solver.max_penetration_jump"), "{message}");
    }
}
