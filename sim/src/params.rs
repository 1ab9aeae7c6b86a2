//! The plain `Copy` parameter structs of the engine: cloth material and solver settings, every
//! field with its unit and default, validated before a run.

use serde::{Deserialize, Serialize};

use crate::error::{Error, Result};

/// Cloth material, the three quantities the datasets sample.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct Material {
    /// Edge spring stiffness k_s, N/m (energy (k_s/2)(|x_i - x_j| - L0)^2 per edge). On an
    /// equilateral mesh the membrane Young's modulus is E_2D = 2 k_s / sqrt(3). Default 100.
    pub stretch: f64,
    /// Area density rho, kg/m^2 (lumped: a vertex carries a third of its triangles' areas).
    /// Default 0.2.
    pub density: f64,
    /// Bending stiffness k_b, N m (Laplacian bending; plate rigidity B = 2 sqrt(3) k_b on
    /// near-equilateral meshes, see docs/PHYSICS.md). Default 1e-5.
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

impl Material {
    /// Checks that every value is finite and positive.
    pub fn validate(&self) -> Result<()> {
        for (name, value, unit) in [
            ("k_s (stretch)", self.stretch, "N/m"),
            ("rho (density)", self.density, "kg/m^2"),
            ("k_b (bending)", self.bending, "N m"),
        ] {
            if !value.is_finite() || value <= 0.0 {
                return Err(Error::Material(format!(
                    "{name} must be a finite positive number of {unit}, got {value}"
                )));
            }
        }
        Ok(())
    }
}

/// Solver settings.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
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
}

fn default_self_contact_distance() -> f64 {
    0.004
}

fn default_self_friction() -> f64 {
    0.3
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
            self_contact: false,
            self_contact_distance: default_self_contact_distance(),
            self_friction: default_self_friction(),
        }
    }
}

impl SolverParams {
    /// Checks ranges: counts at least 1, lengths and speeds finite and non-negative, the
    /// contact offset below the detection band.
    pub fn validate(&self) -> Result<()> {
        if self.substeps == 0 || self.max_iterations == 0 {
            return Err(Error::Setting(
                "substeps and max_iterations must be at least 1".into(),
            ));
        }
        for (name, value) in [
            ("tolerance", self.tolerance),
            ("contact_tolerance", self.contact_tolerance),
            ("contact_offset", self.contact_offset),
            ("max_push_out_speed", self.max_push_out_speed),
            ("air_damping", self.air_damping),
            ("gravity", self.gravity),
            ("max_speed", self.max_speed),
            ("self_contact_distance", self.self_contact_distance),
            ("self_friction", self.self_friction),
        ] {
            if !value.is_finite() || value < 0.0 {
                return Err(Error::Setting(format!(
                    "{name} must be finite and non-negative, got {value}"
                )));
            }
        }
        if self.contact_offset >= self.contact_tolerance && self.contact_tolerance > 0.0 {
            return Err(Error::Setting(format!(
                "contact_offset ({} m) must be smaller than contact_tolerance ({} m)",
                self.contact_offset, self.contact_tolerance
            )));
        }
        if self.self_contact && self.self_contact_distance == 0.0 {
            return Err(Error::Setting(
                "self_contact_distance must be positive when self-contact is on".into(),
            ));
        }
        if self.max_speed == 0.0 {
            return Err(Error::Setting("max_speed must be positive".into()));
        }
        Ok(())
    }
}

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
        assert!(message.contains("k_s"), "{message}");
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
        let params = SolverParams {
            substeps: 0,
            ..SolverParams::default()
        };
        assert!(params.validate().is_err());
    }
}
