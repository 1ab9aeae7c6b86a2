//! The physics regression suite, the engine's first outside client: PHYSICS.md's closed forms
//! as named scenarios, each reporting expected, measured, tolerance and pass, the golden
//! sequences and the drape bench (the peers' scene). `cargo test` runs the fast versions
//! (regress/tests/regression.rs); `dit-garment regress [--long]` prints them all.
//!
//! Scenario groups, one file each: `dynamics.rs` (free fall, momentum, energy, determinism),
//! `friction.rs` (incline, Ly et al.'s drop, accelerating plate), `statics.rs` (hanging chain
//! and sheet, catenary, cantilever), `contact.rs` (sphere drape, convergence),
//! `self_contact.rs` (cloth-cloth contact) and `goldens.rs` (the golden sequences).

use serde::Serialize;

mod contact;
pub mod drape_bench;
mod dynamics;
mod error;
mod friction;
mod goldens;
pub mod self_contact;
mod statics;

pub use error::{Error, Result};
pub use goldens::{
    GOLDEN_TOLERANCE_CM, GOLDENS, Golden, bless, golden_dir, golden_distance, golden_scene,
    simulate_golden,
};

use sim::obstacles::Obstacles;
use sim::{ClothState, Solver, Vec3};

pub(crate) const G: f64 = 9.81;

/// One scenario's result.
#[derive(Debug, Clone, Serialize)]
pub struct Outcome {
    /// Scenario name.
    pub name: String,
    /// Expected value.
    pub expected: f64,
    /// Measured value.
    pub measured: f64,
    /// Allowed |measured - expected|.
    pub tolerance: f64,
    /// Whether |measured - expected| <= tolerance.
    pub pass: bool,
    /// Unit of the three numbers.
    pub unit: String,
}

/// One row of the suite's table: name, expected, measured, tolerance, pass or FAIL, unit.
impl std::fmt::Display for Outcome {
    fn fmt(&self, f: &mut std::fmt::Formatter) -> std::fmt::Result {
        let (name, expected, measured) = (&self.name, self.expected, self.measured);
        let result = if self.pass { "pass" } else { "FAIL" };
        let (tolerance, unit) = (self.tolerance, &self.unit);
        write!(
            f,
            "{name:<40} {expected:>12.6} {measured:>12.6} {tolerance:>11.3e}  {result:<6}  {unit}"
        )
    }
}

impl Outcome {
    pub(crate) fn new(
        name: &str,
        expected: f64,
        measured: f64,
        tolerance: f64,
        unit: &str,
    ) -> Self {
        Self {
            name: name.into(),
            expected,
            measured,
            tolerance,
            pass: (measured - expected).abs() <= tolerance && measured.is_finite(),
            unit: unit.into(),
        }
    }
}

/// A scenario: name and how to run it (`long` = higher resolution / longer runs).
pub struct Scenario {
    /// Name (stable, used by filters and scripts).
    pub name: &'static str,
    /// Runs it.
    pub run: fn(bool) -> Result<Vec<Outcome>>,
}

/// Every scenario, in report order.
pub fn scenarios() -> Vec<Scenario> {
    vec![
        Scenario {
            name: "free_fall",
            run: dynamics::free_fall,
        },
        Scenario {
            name: "momentum",
            run: dynamics::momentum,
        },
        Scenario {
            name: "energy",
            run: dynamics::energy,
        },
        Scenario {
            name: "incline",
            run: friction::incline,
        },
        Scenario {
            name: "ly2020_drop",
            run: friction::ly2020_drop,
        },
        Scenario {
            name: "accelerating_plate",
            run: friction::accelerating_plate,
        },
        Scenario {
            name: "hanging_chain",
            run: statics::hanging_chain,
        },
        Scenario {
            name: "hanging_sheet",
            run: statics::hanging_sheet,
        },
        Scenario {
            name: "catenary",
            run: statics::catenary,
        },
        Scenario {
            name: "cantilever",
            run: statics::cantilever,
        },
        Scenario {
            name: "sphere_drape",
            run: contact::sphere_drape,
        },
        Scenario {
            name: "convergence",
            run: contact::convergence,
        },
        Scenario {
            name: "soft_cloth",
            run: contact::soft_cloth,
        },
        Scenario {
            name: "determinism",
            run: dynamics::determinism,
        },
        Scenario {
            name: "self_contact",
            run: self_contact::self_contact,
        },
        Scenario {
            name: "golden",
            run: goldens::goldens,
        },
    ]
}

/// Runs the scenarios whose name contains `filter` (all if empty).
pub fn run(long: bool, filter: &str) -> Result<Vec<Outcome>> {
    let mut out = Vec::new();
    for s in scenarios().into_iter().filter(|s| s.name.contains(filter)) {
        out.extend((s.run)(long)?);
    }
    Ok(out)
}

fn advance(
    solver: &mut Solver,
    state: &mut ClothState,
    obstacles: &mut Obstacles,
    frames: std::ops::Range<usize>,
    frame_dt: f64,
) -> Result<()> {
    for k in frames {
        solver.advance_frame(state, obstacles, k as f64 * frame_dt, k)?;
    }
    Ok(())
}

fn mean(v: &[Vec3]) -> Vec3 {
    v.iter().sum::<Vec3>() / v.len() as f64
}
