//! The projective-dynamics step with exact frictional contact (Ly et al. 2020), as named,
//! timed stages over plain data:
//!
//! 1. `predict`: v* = v + h g (pinned vertices get their prescribed velocity);
//! 2. `detect`: obstacles move to the end of the step and report contacts at x + h v*; with
//!    self-contact on, vertices close to triangles of the same cloth become node pairs;
//! 3. `damp`: air damping of the carried velocity;
//! 4. `prepare`: the step's contact counts, A x_n and the contact nodes' effective masses;
//! 5. the iteration: `local` projections -> right-hand side -> `contact` impulses per node,
//!    then `self_contact` pair impulses -> global `solve` with the constant factorization ->
//!    `residual`, until the residual is below tolerance;
//! 6. `finish`: x = x + h v.
//!
//! Files: `setup.rs` (what a cloth is, the solver built from it), `step.rs` (the stages),
//! `contacts.rs` (the contact stages).
//!
//! Velocity-level backward Euler: P v = M v* + h sum_t w_t A_t^T (p_t - A_t x_n) + r with
//! P = M + h^2 sum_t w_t A_t^T A_t. Contacts only change r, never P.

mod anderson;
mod contacts;
mod setup;
mod step;

pub use setup::ClothSetup;

use std::collections::BTreeMap;
use std::time::Instant;

use serde::{Deserialize, Serialize};

use crate::cloth::{ClothState, Vec3};
use crate::constraints::{Constraints, ProjectionInputs};
use crate::contact::Contact;
use crate::error::{BlowUpCause, Error, Result};
use crate::obstacles::Obstacles;
use crate::params::SolverParams;
use crate::self_contact::{SelfContact, SelfContactDetector};
use crate::system::{GlobalSystem, Symbolic};

/// Bending is lagged (left out of the factorized matrix) when it adds less than this share to
/// the matrix diagonal; see `system.rs`. The default material on the built-in skirt has 7.8%
/// (lagging it halves the solve time); k_b = 1e-4 has 78% and stays in the matrix.
const LAGGED_BENDING_SHARE: f64 = 0.1;

/// Under-relaxation of the contact impulses between iterations (see `contact_step`).
const IMPULSE_RELAXATION: f64 = 0.5;

/// A step whose velocities would still carry a vertex through a triangle of the same cloth
/// after `max_iterations` keeps iterating until they do not, up to this many times
/// `max_iterations`. The iteration stops before it converges, and where two bodies pinch
/// layers (a long skirt's panels between the legs) what it leaves crosses them (measured on
/// the long-skirt walk at 4 x 16, most crossing triangle pairs of a frame: 58 with no extra
/// iterations, 28 at up to 2x, 6 at up to 4x, for 30% more time on that run).
const CROSSING_ITERATION_FACTOR: usize = 4;

/// Floor on a contact node's response to its patch's impulses (see `effective_masses`), so a
/// node that barely moves cannot get an unbounded effective mass.
const MIN_PATCH_RESPONSE: f64 = 1e-6;

/// The timed stages of a step (see the module docs), and factorization.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Stage {
    /// v* = v + h g, the predicted positions.
    Predict,
    /// Obstacle update: the body interpolated to the step's end, its BVH refit.
    Refit,
    /// Body contact detection (closest-point and inside queries).
    Detect,
    /// Cloth-cloth contact detection (broad and narrow phase).
    SelfDetect,
    /// Air damping of the carried velocity.
    Damp,
    /// Contact counts, A x_n and the effective masses of contact nodes and pairs.
    Prepare,
    /// Local projections and the right-hand side.
    Local,
    /// Body contact impulses.
    Contact,
    /// Cloth-cloth pair impulses.
    SelfContact,
    /// Global solves.
    Solve,
    /// Residuals of the iteration.
    Residual,
    /// Anderson acceleration of the iterate.
    Accelerate,
    /// x = x + h v.
    Finish,
    /// Factorizations (a new step size).
    Factorize,
}

/// Wall time spent in each stage since the last reset, s.
#[derive(Debug, Clone, Copy, Default, PartialEq, Serialize)]
pub struct StageTimes {
    /// [`Stage::Predict`].
    pub predict: f64,
    /// [`Stage::Refit`].
    pub refit: f64,
    /// [`Stage::Detect`].
    pub detect: f64,
    /// [`Stage::SelfDetect`].
    pub self_detect: f64,
    /// [`Stage::Damp`].
    pub damp: f64,
    /// [`Stage::Prepare`].
    pub prepare: f64,
    /// [`Stage::Local`].
    pub local: f64,
    /// [`Stage::Contact`].
    pub contact: f64,
    /// [`Stage::SelfContact`].
    pub self_contact: f64,
    /// [`Stage::Solve`].
    pub solve: f64,
    /// [`Stage::Residual`].
    pub residual: f64,
    /// [`Stage::Accelerate`].
    pub accelerate: f64,
    /// [`Stage::Finish`].
    pub finish: f64,
    /// [`Stage::Factorize`].
    pub factorize: f64,
}

impl StageTimes {
    /// The counter of `stage`, s.
    pub fn of(&mut self, stage: Stage) -> &mut f64 {
        match stage {
            Stage::Predict => &mut self.predict,
            Stage::Refit => &mut self.refit,
            Stage::Detect => &mut self.detect,
            Stage::SelfDetect => &mut self.self_detect,
            Stage::Damp => &mut self.damp,
            Stage::Prepare => &mut self.prepare,
            Stage::Local => &mut self.local,
            Stage::Contact => &mut self.contact,
            Stage::SelfContact => &mut self.self_contact,
            Stage::Solve => &mut self.solve,
            Stage::Residual => &mut self.residual,
            Stage::Accelerate => &mut self.accelerate,
            Stage::Finish => &mut self.finish,
            Stage::Factorize => &mut self.factorize,
        }
    }
}

/// What one step did.
#[derive(Debug, Clone, Copy, Default, PartialEq, Serialize)]
pub struct StepReport {
    /// Local-global iterations run.
    pub iterations: usize,
    /// Final residual, m/s (largest velocity change of the last iteration or contact
    /// Alart-Curnier residual per unit mass).
    pub residual: f64,
    /// Contacts in the step.
    pub contacts: usize,
    /// Contacts whose vertex was deeper inside an obstacle than the contact band.
    pub deep_contacts: usize,
    /// Deepest penetration among the contacts at the start of the step, m (0 if none).
    pub max_depth: f64,
    /// Cloth-cloth contact pairs in the step.
    pub self_contacts: usize,
}

/// What one output frame did (several steps).
#[derive(Debug, Clone, Copy, Default, PartialEq, Serialize, Deserialize)]
pub struct FrameReport {
    /// Steps taken (substeps x 2^retries).
    pub steps: usize,
    /// Iterations summed over the steps.
    pub iterations: usize,
    /// Largest iteration count of a step.
    pub max_iterations: usize,
    /// Largest final residual of a step, m/s.
    pub max_residual: f64,
    /// Largest contact count of a step.
    pub contacts: usize,
    /// Deep contacts (inside deeper than the band) summed over the steps.
    pub deep_contacts: usize,
    /// Deepest penetration seen at the start of a step, m.
    pub max_depth: f64,
    /// Retries with smaller steps this frame needed.
    pub retries: usize,
    /// Largest cloth-cloth contact pair count of a step.
    #[serde(default)]
    pub self_contacts: usize,
}

struct Workspace {
    v_star: Vec<Vec3>,
    predicted: Vec<Vec3>,
    positions: Vec<Vec3>,
    ax_start: Vec<Vec3>,
    q: Vec<Vec3>,
    rhs: Vec<Vec3>,
    v: Vec<Vec3>,
    v_next: Vec<Vec3>,
    contacts: Vec<Contact>,
    impulses: Vec<Vec3>,
    effective_mass: Vec<f64>,
    in_contact: Vec<bool>,
    self_contacts: Vec<SelfContact>,
    self_impulses: Vec<Vec3>,
    /// Reduced mass of each pair.
    self_mass: Vec<f64>,
    /// Nodes (not pinned) in some pair, each once.
    self_nodes: Vec<u32>,
    /// Effective mass of the nodes in `self_nodes` (indexed by vertex).
    node_mass: Vec<f64>,
    /// m_j v_j - (P v)_j of the nodes in `self_nodes` (indexed by vertex).
    node_free: Vec<Vec3>,
    /// M 1_C: each contact node's mass (see `effective_masses`).
    patch_load: Vec<f64>,
    /// P^-1 M 1_C.
    patch_response: Vec<f64>,
}

/// The solver: factorized system, constraints and workspace for one cloth.
pub struct Solver {
    setup: ClothSetup,
    params: SolverParams,
    frame_dt: f64,
    masses: Vec<f64>,
    constraints: Constraints,
    incidence_ptr: Vec<usize>,
    incidence: Vec<(u32, f64)>,
    pinned: Vec<bool>,
    pin_targets: Vec<Vec3>,
    attachment_targets: Vec<Vec3>,
    seam_length_cap: f64,
    systems: BTreeMap<usize, GlobalSystem>,
    symbolic: [Option<Symbolic>; 2],
    self_contact: Option<SelfContactDetector>,
    ws: Workspace,
    times: StageTimes,
    anderson: Option<anderson::Anderson>,
}

impl Solver {
    /// Runs one stage, adding its wall time to the stage's counter (every stage
    /// and factorization go through here).
    pub(super) fn timed<R>(&mut self, stage: Stage, run: impl FnOnce(&mut Self) -> R) -> R {
        let started = Instant::now();
        let result = run(self);
        *self.times.of(stage) += started.elapsed().as_secs_f64();
        result
    }

    /// The cloth setup.
    pub fn setup(&self) -> &ClothSetup {
        &self.setup
    }

    /// Solver settings.
    pub fn params(&self) -> &SolverParams {
        &self.params
    }

    /// Lumped vertex masses, kg.
    pub fn masses(&self) -> &[f64] {
        &self.masses
    }

    /// Stage times accumulated since the last call, and resets them.
    pub fn take_times(&mut self) -> StageTimes {
        std::mem::take(&mut self.times)
    }

    /// Sets where pinned vertices must be at the end of the coming steps (all vertices'
    /// targets; only pinned ones are used). Default: the rest positions.
    pub fn set_pin_targets(&mut self, targets: &[Vec3]) {
        self.pin_targets.copy_from_slice(targets);
    }

    /// Sets the attachments' target points, in the setup's attachment order.
    pub fn set_attachment_targets(&mut self, targets: &[Vec3]) {
        self.attachment_targets.copy_from_slice(targets);
    }

    /// Sets gravity (m/s^2, acting along -y) and air damping (1/s); neither is part of the
    /// factorized matrix, so this is free (sewing closes seams without gravity, then drapes).
    pub fn set_gravity_and_damping(&mut self, gravity: f64, air_damping: f64) {
        self.params.gravity = gravity;
        self.params.air_damping = air_damping;
    }

    /// Caps the gap every seam keeps, m: infinite (the start) = no pull, 0 = fully closed.
    /// Lowering it frame by frame closes seams at a bounded speed (the seam ramp).
    pub fn set_seam_length_cap(&mut self, cap: f64) {
        self.seam_length_cap = cap.max(0.0);
    }

    /// Potential energy of the constraints at `positions` (gravity excluded), J.
    pub fn elastic_energy(&self, positions: &[Vec3]) -> f64 {
        self.constraints.energy(positions, &self.inputs())
    }

    /// Kinetic energy of `state`, J.
    pub fn kinetic_energy(&self, state: &ClothState) -> f64 {
        state
            .velocities
            .iter()
            .zip(&self.masses)
            .map(|(v, m)| 0.5 * m * v.norm_squared())
            .sum()
    }

    fn inputs(&self) -> ProjectionInputs<'_> {
        ProjectionInputs {
            seam_length_cap: self.seam_length_cap,
            attachment_targets: &self.attachment_targets,
        }
    }

    /// Advances one output frame starting at time `t0` (s): `params.substeps` steps, retried
    /// with twice as many steps (up to `max_retries` times) if a step produces non-finite
    /// values or a vertex faster than `max_speed`. On failure `state` is left as it was.
    pub fn advance_frame(
        &mut self,
        state: &mut ClothState,
        obstacles: &mut Obstacles,
        t0: f64,
        frame: usize,
    ) -> Result<FrameReport> {
        self.advance_frame_from(state, obstacles, t0, frame, 0)
    }

    /// [`Self::advance_frame`] starting at retry `first_retry` (`substeps << first_retry`
    /// steps): how a caller whose own check rejected the frame runs it again, finer.
    pub fn advance_frame_from(
        &mut self,
        state: &mut ClothState,
        obstacles: &mut Obstacles,
        t0: f64,
        frame: usize,
        first_retry: usize,
    ) -> Result<FrameReport> {
        let saved = state.clone();
        let mut reason = BlowUpCause::NonFinite;
        for retry in first_retry..=self.params.max_retries {
            let substeps = self.params.substeps << retry;
            self.system_for(substeps)?;
            let h = self.frame_dt / substeps as f64;
            let mut report = FrameReport {
                retries: retry,
                ..FrameReport::default()
            };
            let mut failed = None;
            for s in 0..substeps {
                let step = self.step(state, obstacles, substeps, t0 + (s + 1) as f64 * h)?;
                report.steps += 1;
                report.iterations += step.iterations;
                report.max_iterations = report.max_iterations.max(step.iterations);
                report.max_residual = report.max_residual.max(step.residual);
                report.contacts = report.contacts.max(step.contacts);
                report.deep_contacts += step.deep_contacts;
                report.max_depth = report.max_depth.max(step.max_depth);
                report.self_contacts = report.self_contacts.max(step.self_contacts);
                if let Some(problem) = self.check(state) {
                    failed = Some(problem);
                    break;
                }
            }
            match failed {
                None => return Ok(report),
                Some(problem) => {
                    reason = problem;
                    *state = saved.clone();
                }
            }
        }
        Err(Error::BlowUp {
            frame,
            reason,
            retries: self.params.max_retries,
        })
    }

    fn check(&self, state: &ClothState) -> Option<BlowUpCause> {
        if !state.is_finite() {
            return Some(BlowUpCause::NonFinite);
        }
        let (i, speed) = state
            .velocities
            .iter()
            .enumerate()
            .map(|(i, v)| (i, v.norm()))
            .fold((0, 0.0), |a, b| if b.1 > a.1 { b } else { a });
        (speed > self.params.max_speed).then_some(BlowUpCause::TooFast {
            vertex: i,
            speed,
            limit: self.params.max_speed,
        })
    }
}
