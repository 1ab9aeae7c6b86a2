//! The plain `Copy` parameter structs of the engine: cloth material and solver settings, every
//! field with its unit and default, validated before a run.

use serde::{Deserialize, Serialize};

use crate::error::{Error, Result};

/// Cloth material, the three quantities the datasets sample: the one material type of the
/// project (command line, scene configuration, dataset plan, recordings and the surrogate's
/// conditions). Its serialized names carry the units, as recordings write them.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Material {
    /// Edge spring stiffness k_s, N/m (energy (k_s/2)(|x_i - x_j| - L0)^2 per edge). On an
    /// equilateral mesh the membrane Young's modulus is E_2D = 2 k_s / sqrt(3). Default 100.
    #[serde(rename = "k_s_n_per_m")]
    pub stretch: f64,
    /// Area density rho, kg/m^2 (lumped: a vertex carries a third of its triangles' areas).
    /// Default 0.2.
    #[serde(rename = "rho_kg_per_m2")]
    pub density: f64,
    /// Bending stiffness k_b, N m (Laplacian bending; plate rigidity B = 2 sqrt(3) k_b on
    /// near-equilateral meshes, see docs/PHYSICS.md). Default 1e-5.
    #[serde(rename = "k_b_n_m")]
    pub bending: f64,
}

impl Default for Material {
    fn default() -> Self {
        Self {
            stretch: 100.0,
            density: 0.2,
            bending: 1e-5,
        }
    }
}

/// The material values accepted, (key, smallest, largest, unit): wide around cloth (silk to
/// canvas: k_s 10-10^4 N/m, rho 0.02-1 kg/m^2, k_b 10^-8-10^-3 N m) but bounded, so no
/// command (`simulate`, `predict`, a dataset spec) takes a value that overflows the solver or
/// the surrogate's normalized conditions (k_s = 1e300 gave non-finite predictions).
pub const MATERIAL_BOUNDS: [(&str, f64, f64, &str); 3] = [
    ("material.k_s_n_per_m", 1e-3, 1e6, "N/m"),
    ("material.rho_kg_per_m2", 1e-4, 100.0, "kg/m^2"),
    ("material.k_b_n_m", 1e-14, 10.0, "N m"),
];

impl Material {
    /// Checks that every value is finite and within [`MATERIAL_BOUNDS`]; the error names the
    /// configuration key. The one check of material values, for every command.
    pub fn validate(&self) -> Result<()> {
        let values = [self.stretch, self.density, self.bending];
        for ((key, low, high, unit), value) in MATERIAL_BOUNDS.into_iter().zip(values) {
            if !(value.is_finite() && (low..=high).contains(&value)) {
                return Err(Error::value(
                    key,
                    value,
                    &format!("must be a number of {unit} from {low:e} to {high:e}"),
                ));
            }
        }
        Ok(())
    }

    /// This material with the values of `k_s=..,rho=..,k_b=..` (any subset, the command line's
    /// `--material`) put in; not validated (the scene configuration is, once).
    pub fn with_overrides(mut self, text: &str) -> Result<Self> {
        let bad = |value: &str, expected: &str| Error::value("--material", value, expected);
        for part in text.split(',').map(str::trim).filter(|p| !p.is_empty()) {
            let (key, value) = part
                .split_once('=')
                .ok_or_else(|| bad(part, "must be key=value (keys k_s, rho, k_b)"))?;
            let number: f64 = value
                .trim()
                .parse()
                .map_err(|_| bad(part, "the value is not a number"))?;
            match key.trim() {
                "k_s" => self.stretch = number,
                "rho" => self.density = number,
                "k_b" => self.bending = number,
                _ => return Err(bad(part, "unknown key (keys k_s N/m, rho kg/m^2, k_b N m)")),
            }
        }
        Ok(self)
    }
}

/// Solver settings.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct SolverParams {
    /// Substeps per output frame (the time step is frame time / substeps). Default 4.
    pub substeps: usize,
    /// Maximum local-global iterations per substep. Default 20. With self-contact on, a step
    /// whose velocities would still carry a vertex through a layer keeps iterating, up to 4
    /// times this (the frame statistics report the iterations run).
    pub max_iterations: usize,
    /// Convergence tolerance on the residual, m/s: the largest velocity change of an iteration
    /// and the largest Alart-Curnier contact residual (divided by the node mass). Default 1e-4.
    pub tolerance: f64,
    /// Contact detection band, m: a vertex whose predicted position is closer to an obstacle
    /// than this becomes a contact candidate. Default 0.01.
    pub contact_tolerance: f64,
    /// Gap the contact solve keeps between cloth vertices and obstacle surfaces, m (the cloth's
    /// collision thickness). Default 0.003.
    pub contact_offset: f64,
    /// Fastest speed, m/s, at which a vertex found inside an obstacle is pushed back out
    /// (relative to the obstacle). Default 1.0.
    pub max_push_out_speed: f64,
    /// Air damping, 1/s (a force -alpha m v, off at contact nodes). Default 0.
    pub air_damping: f64,
    /// Gravity, m/s^2, along -y. Default 9.81.
    pub gravity: f64,
    /// Retries of a frame that blew up, each with twice the substeps. Default 3.
    pub max_retries: usize,
    /// A vertex faster than this (m/s) counts as an explosion. Default 50.
    pub max_speed: f64,
    /// The most the deepest penetration into the body (away from the body's own overlaps) may
    /// grow in one frame, m. A frame that deepens it more is run again with twice the
    /// substeps (up to `max_retries` times, while each retry ends shallower), and the
    /// shallowest attempt is kept: a limb that sweeps past light cloth in one substep leaves it
    /// inside (docs/BENCHMARKS.md, the soft-cloth blow-up). 0 turns the check off. Default
    /// 0.01.
    #[serde(default = "default_max_penetration_jump")]
    pub max_penetration_jump: f64,
    /// Cloth-cloth contact (vertex against triangle of the same cloth). Off in this plain
    /// default; garment scenes turn it on (`--no-self-contact` turns it off).
    #[serde(default)]
    pub self_contact: bool,
    /// Gap self-contact keeps between a vertex and a triangle of the same cloth, m (two
    /// layers rest this far apart; pairs within twice this are solved). Default 0.004.
    #[serde(default = "default_self_contact_distance")]
    pub self_contact_distance: f64,
    /// Coulomb friction coefficient between touching layers of cloth. Default 0.3.
    #[serde(default = "default_self_friction")]
    pub self_friction: f64,
    /// Anderson acceleration: how many past iterations each iterate mixes in (0 = off, at
    /// most 8; see `solver/anderson.rs`). Default 0: at the same iterations it lowers the
    /// residual and the depth on the skirt, but fewer accelerated iterations do not yet match
    /// 16 plain ones on every garment (docs/BENCHMARKS.md).
    #[serde(default)]
    pub acceleration: usize,
}

fn default_self_contact_distance() -> f64 {
    0.004
}

fn default_self_friction() -> f64 {
    0.3
}

fn default_max_penetration_jump() -> f64 {
    0.01
}

impl Default for SolverParams {
    fn default() -> Self {
        Self {
            substeps: 4,
            max_iterations: 20,
            tolerance: 1e-4,
            contact_tolerance: 0.01,
            contact_offset: 0.003,
            max_push_out_speed: 1.0,
            air_damping: 0.0,
            gravity: 9.81,
            max_retries: 3,
            max_speed: 50.0,
            max_penetration_jump: default_max_penetration_jump(),
            self_contact: false,
            self_contact_distance: default_self_contact_distance(),
            self_friction: default_self_friction(),
            acceleration: 0,
        }
    }
}

impl SolverParams {
    /// Checks ranges: counts at least 1, lengths and speeds finite and non-negative, the
    /// contact offset below the detection band.
    pub fn validate(&self) -> Result<()> {
        for (key, value) in [
            ("solver.substeps", self.substeps),
            ("solver.max_iterations", self.max_iterations),
        ] {
            if value == 0 {
                return Err(Error::value(key, value, "must be at least 1"));
            }
            if value > MAX_STEP_COUNT {
                return Err(Error::value(
                    key,
                    value,
                    &format!("must be at most {MAX_STEP_COUNT}"),
                ));
            }
        }
        // Work per frame grows as their product (and doubles per retry).
        let work = self.substeps * self.max_iterations;
        if work > MAX_STEP_WORK {
            return Err(Error::value(
                "solver.substeps x solver.max_iterations",
                work,
                &format!("must be at most {MAX_STEP_WORK}"),
            ));
        }
        if self.acceleration > MAX_ACCELERATION {
            return Err(Error::value(
                "solver.acceleration",
                self.acceleration,
                &format!("must be at most {MAX_ACCELERATION}"),
            ));
        }
        if self.max_retries > MAX_RETRIES {
            return Err(Error::value(
                "solver.max_retries",
                self.max_retries,
                &format!("must be at most {MAX_RETRIES} (each retry doubles the substeps)"),
            ));
        }
        for (key, value) in [
            ("solver.tolerance", self.tolerance),
            ("solver.contact_tolerance", self.contact_tolerance),
            ("solver.contact_offset", self.contact_offset),
            ("solver.max_push_out_speed", self.max_push_out_speed),
            ("solver.air_damping", self.air_damping),
            ("solver.gravity", self.gravity),
            ("solver.max_speed", self.max_speed),
            ("solver.max_penetration_jump", self.max_penetration_jump),
            ("solver.self_contact_distance", self.self_contact_distance),
            ("solver.self_friction", self.self_friction),
        ] {
            if !value.is_finite() || value < 0.0 {
                return Err(Error::value(key, value, "must be finite and non-negative"));
            }
        }
        if self.contact_offset >= self.contact_tolerance && self.contact_tolerance > 0.0 {
            return Err(Error::value(
                "solver.contact_offset",
                self.contact_offset,
                &format!(
                    "must be smaller than solver.contact_tolerance ({} m)",
                    self.contact_tolerance
                ),
            ));
        }
        if self.self_contact_distance > MAX_SELF_CONTACT_DISTANCE_M {
            return Err(Error::value(
                "solver.self_contact_distance",
                self.self_contact_distance,
                &format!(
                    "must be at most {MAX_SELF_CONTACT_DISTANCE_M} m (a wider gap makes every \
                     vertex a candidate of every triangle)"
                ),
            ));
        }
        if self.self_contact && self.self_contact_distance == 0.0 {
            return Err(Error::value(
                "solver.self_contact_distance",
                0,
                "must be positive when self-contact is on",
            ));
        }
        if self.max_speed == 0.0 {
            return Err(Error::value("solver.max_speed", 0, "must be positive"));
        }
        Ok(())
    }
}

/// Largest substep or iteration count a configuration may ask for (larger values are typos
/// that would run for days).
pub const MAX_STEP_COUNT: usize = 4096;

/// The most substeps times iterations per frame (the 4 x 16 default is 64).
pub const MAX_STEP_WORK: usize = 65_536;

/// The widest gap self-contact may keep between layers, m.
pub const MAX_SELF_CONTACT_DISTANCE_M: f64 = 0.05;

/// The most past iterations Anderson acceleration mixes in.
pub const MAX_ACCELERATION: usize = 8;

/// Largest retry count (each retry doubles the substeps of the frame).
pub const MAX_RETRIES: usize = 8;

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn defaults_are_valid_and_bad_values_are_named() {
        Material::default().validate().unwrap();
        SolverParams::default().validate().unwrap();
        let bad = Material {
            stretch: -1.0,
            ..Material::default()
        };
        let message = bad.validate().unwrap_err().to_string();
        assert!(message.contains("material.k_s_n_per_m = -1"), "{message}");
        let zero = Material {
            density: 0.0,
            ..Material::default()
        };
        assert!(zero.validate().unwrap_err().to_string().contains("rho"));
        let nan = Material {
            bending: f64::NAN,
            ..Material::default()
        };
        assert!(nan.validate().is_err());
        let huge = Material {
            stretch: 1e300,
            ..Material::default()
        };
        let message = huge.validate().unwrap_err().to_string();
        assert!(message.contains("from 1e-3 to 1e6"), "{message}");
        let params = SolverParams {
            substeps: 0,
            ..SolverParams::default()
        };
        assert!(params.validate().is_err());
        let m = Material::default()
            .with_overrides("k_s=150, rho=0.3")
            .unwrap();
        assert_eq!((m.stretch, m.density, m.bending), (150.0, 0.3, 1e-5));
        let message = Material::default()
            .with_overrides("k_x=1")
            .unwrap_err()
            .to_string();
        assert!(message.contains("k_x=1"), "{message}");
    }
}
