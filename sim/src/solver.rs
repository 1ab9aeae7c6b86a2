//! The projective-dynamics step with exact frictional contact (Ly et al. 2020), as named,
//! timed stages over plain data:
//!
//! 1. `predict`: v* = v + h g (pinned vertices get their prescribed velocity);
//! 2. `detect`: obstacles move to the end of the step and report contacts at x + h v*; with
//!    self-contact on, vertices close to triangles of the same cloth become node pairs;
//! 3. `iterate`: local projections -> right-hand side -> per-node contact impulses, then
//!    cloth-cloth pair impulses -> global solve with the constant factorization, until the
//!    residual is below tolerance;
//! 4. `finish`: x = x + h v.
//!
//! Velocity-level backward Euler: P v = M v* + h sum_t w_t A_t^T (p_t - A_t x_n) + r with
//! P = M + h^2 sum_t w_t A_t^T A_t. Contacts only change r, never P.

use std::collections::BTreeMap;
use std::time::{Duration, Instant};

use rayon::prelude::*;
use serde::{Deserialize, Serialize};

use crate::cloth::{ClothMesh, ClothState, Vec3};
use crate::constraints::{Attachment, BendingRest, Constraints, ProjectionInputs, Seam, Spring};
use crate::contact::{Contact, alart_curnier, cone_impulse};
use crate::error::{Error, Result};
use crate::obstacles::{DetectionInput, Obstacle};
use crate::params::{Material, SolverParams};
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

/// Everything that defines a cloth besides its state: mesh, material and constraints.
#[derive(Debug, Clone)]
pub struct ClothSetup {
    /// Mesh (its rest shape gives rest lengths and the curved bending rest state).
    pub mesh: ClothMesh,
    /// Material.
    pub material: Material,
    /// Bending rest state.
    pub bending_rest: BendingRest,
    /// Seams (zero-length springs) between vertex pairs.
    pub seams: Vec<Seam>,
    /// Extra springs with their own rest length and stiffness.
    pub springs: Vec<Spring>,
    /// Springs to moving targets (set with [`Solver::set_attachment_targets`]).
    pub attachments: Vec<Attachment>,
    /// Pinned vertices (velocity prescribed by their target positions).
    pub pins: Vec<u32>,
}

impl ClothSetup {
    /// A free cloth with a flat bending rest state.
    pub fn new(mesh: ClothMesh, material: Material) -> Self {
        Self {
            mesh,
            material,
            bending_rest: BendingRest::Flat,
            seams: Vec::new(),
            springs: Vec::new(),
            attachments: Vec::new(),
            pins: Vec::new(),
        }
    }
}

/// Wall time spent in each stage since the last reset.
#[derive(Debug, Clone, Copy, Default, Serialize)]
pub struct StageTimes {
    /// Prediction and damping.
    pub predict: Duration,
    /// Obstacle update (BVH refit) and contact detection.
    pub detect: Duration,
    /// Local projections and right-hand side.
    pub local: Duration,
    /// Contact impulses and residuals.
    pub contact: Duration,
    /// Global solves.
    pub solve: Duration,
    /// Factorizations (new material or step size).
    pub factorize: Duration,
}

impl StageTimes {
    /// Adds another set of times.
    pub fn add(&mut self, other: &StageTimes) {
        self.predict += other.predict;
        self.detect += other.detect;
        self.local += other.local;
        self.contact += other.contact;
        self.solve += other.solve;
        self.factorize += other.factorize;
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
}

impl Solver {
    /// Validates the setup and factorizes the global matrix for `params.substeps` steps per
    /// frame of `frame_dt` seconds.
    pub fn new(setup: ClothSetup, params: SolverParams, frame_dt: f64) -> Result<Self> {
        setup.material.validate()?;
        params.validate()?;
        if !(frame_dt.is_finite() && frame_dt > 0.0) {
            return Err(Error::Setting(format!(
                "frame time must be positive, got {frame_dt}"
            )));
        }
        let n = setup.mesh.num_vertices();
        for &p in &setup.pins {
            if p as usize >= n {
                return Err(Error::Setting(format!(
                    "pinned vertex {p} does not exist ({n} vertices)"
                )));
            }
        }
        for s in &setup.seams {
            if s.a as usize >= n
                || s.b as usize >= n
                || s.a == s.b
                || !(s.stiffness > 0.0 && s.stiffness.is_finite())
            {
                return Err(Error::Setting(format!("bad seam {s:?} ({n} vertices)")));
            }
        }
        for s in &setup.springs {
            if s.a as usize >= n
                || s.b as usize >= n
                || s.a == s.b
                || !(s.stiffness > 0.0 && s.stiffness.is_finite())
                || !(s.rest_length >= 0.0 && s.rest_length.is_finite())
            {
                return Err(Error::Setting(format!("bad spring {s:?} ({n} vertices)")));
            }
        }
        for a in &setup.attachments {
            if a.vertex as usize >= n || !(a.stiffness > 0.0 && a.stiffness.is_finite()) {
                return Err(Error::Setting(format!(
                    "bad attachment {a:?} ({n} vertices)"
                )));
            }
        }
        let masses = setup.mesh.lumped_masses(setup.material.density);
        let constraints = Constraints::build(
            &setup.mesh,
            &setup.material,
            setup.bending_rest,
            &setup.seams,
            &setup.springs,
            &setup.attachments,
        );
        let (incidence_ptr, incidence) = constraints.incidence(n);
        let mut pinned = vec![false; n];
        for &p in &setup.pins {
            pinned[p as usize] = true;
        }
        let pin_targets = setup.mesh.rest().to_vec();
        let attachment_targets = setup
            .attachments
            .iter()
            .map(|a| setup.mesh.rest()[a.vertex as usize])
            .collect();
        let terms = constraints.len();
        let self_contact = params.self_contact.then(|| {
            let seams: Vec<[u32; 2]> = setup.seams.iter().map(|s| [s.a, s.b]).collect();
            SelfContactDetector::new(n, setup.mesh.triangles(), setup.mesh.edges(), &seams)
        });
        let mut solver = Self {
            params,
            frame_dt,
            masses,
            constraints,
            incidence_ptr,
            incidence,
            pinned,
            pin_targets,
            attachment_targets,
            seam_length_cap: f64::INFINITY,
            systems: BTreeMap::new(),
            symbolic: [None, None],
            self_contact,
            ws: Workspace {
                v_star: vec![Vec3::zeros(); n],
                predicted: vec![Vec3::zeros(); n],
                positions: vec![Vec3::zeros(); n],
                ax_start: vec![Vec3::zeros(); terms],
                q: vec![Vec3::zeros(); terms],
                rhs: vec![Vec3::zeros(); n],
                v: vec![Vec3::zeros(); n],
                v_next: vec![Vec3::zeros(); n],
                contacts: Vec::new(),
                impulses: Vec::new(),
                effective_mass: Vec::new(),
                in_contact: vec![false; n],
                self_contacts: Vec::new(),
                self_impulses: Vec::new(),
                self_mass: Vec::new(),
                self_nodes: Vec::new(),
                node_mass: vec![0.0; n],
                node_free: vec![Vec3::zeros(); n],
                patch_load: vec![0.0; n],
                patch_response: vec![0.0; n],
            },
            times: StageTimes::default(),
            setup,
        };
        solver.system_for(params.substeps)?;
        Ok(solver)
    }

    /// Replaces the material: new weights and masses, the same symbolic analysis.
    pub fn set_material(&mut self, material: Material) -> Result<()> {
        material.validate()?;
        self.setup.material = material;
        self.masses = self.setup.mesh.lumped_masses(material.density);
        self.constraints = Constraints::build(
            &self.setup.mesh,
            &material,
            self.setup.bending_rest,
            &self.setup.seams,
            &self.setup.springs,
            &self.setup.attachments,
        );
        let (ptr, inc) = self.constraints.incidence(self.masses.len());
        self.incidence_ptr = ptr;
        self.incidence = inc;
        self.systems.clear();
        self.system_for(self.params.substeps)?;
        Ok(())
    }

    fn system_for(&mut self, substeps: usize) -> Result<()> {
        if !self.systems.contains_key(&substeps) {
            let started = Instant::now();
            let h = self.frame_dt / substeps as f64;
            let share = self.constraints.bending_share(&self.masses, h);
            let lag = share < LAGGED_BENDING_SHARE;
            let system = GlobalSystem::new(
                &self.masses,
                &self.constraints,
                h,
                &self.pinned,
                lag,
                self.symbolic[lag as usize].clone(),
            )?;
            self.symbolic[lag as usize] = Some(system.symbolic());
            self.systems.insert(substeps, system);
            self.times.factorize += started.elapsed();
        }
        Ok(())
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
        obstacles: &mut [Box<dyn Obstacle>],
        t0: f64,
        frame: usize,
    ) -> Result<FrameReport> {
        let saved = state.clone();
        let mut reason = String::new();
        for retry in 0..=self.params.max_retries {
            let substeps = self.params.substeps << retry;
            self.system_for(substeps)?;
            let h = self.frame_dt / substeps as f64;
            let mut report = FrameReport {
                retries: retry,
                ..FrameReport::default()
            };
            let mut failed = None;
            for s in 0..substeps {
                let step = self.step(state, obstacles, substeps, t0 + (s + 1) as f64 * h);
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

    fn check(&self, state: &ClothState) -> Option<String> {
        if !state.is_finite() {
            return Some("non-finite position or velocity".into());
        }
        let (i, speed) = state
            .velocities
            .iter()
            .enumerate()
            .map(|(i, v)| (i, v.norm()))
            .fold((0, 0.0), |a, b| if b.1 > a.1 { b } else { a });
        (speed > self.params.max_speed).then(|| {
            format!(
                "vertex {i} reached {speed:.1} m/s (limit {} m/s): energy explosion",
                self.params.max_speed
            )
        })
    }

    /// One step of length frame_dt / `substeps` ending at time `t_end`.
    pub fn step(
        &mut self,
        state: &mut ClothState,
        obstacles: &mut [Box<dyn Obstacle>],
        substeps: usize,
        t_end: f64,
    ) -> StepReport {
        let h = self.frame_dt / substeps as f64;
        self.predict(state, h);
        self.detect(state, obstacles, h, t_end);
        self.damp(h);
        let report = self.iterate(state, substeps, h);
        // finish
        for ((x, v), v_new) in state
            .positions
            .iter_mut()
            .zip(state.velocities.iter_mut())
            .zip(&self.ws.v)
        {
            *v = *v_new;
            *x += h * v_new;
        }
        report
    }

    fn predict(&mut self, state: &ClothState, h: f64) {
        let started = Instant::now();
        let g = Vec3::new(0.0, -self.params.gravity, 0.0);
        for i in 0..state.positions.len() {
            let v = if self.pinned[i] {
                (self.pin_targets[i] - state.positions[i]) / h
            } else {
                state.velocities[i] + h * g
            };
            self.ws.v_star[i] = v;
            self.ws.predicted[i] = state.positions[i] + h * v;
        }
        self.times.predict += started.elapsed();
    }

    fn detect(
        &mut self,
        state: &ClothState,
        obstacles: &mut [Box<dyn Obstacle>],
        h: f64,
        t_end: f64,
    ) {
        let started = Instant::now();
        let ws = &mut self.ws;
        ws.contacts.clear();
        let input = DetectionInput {
            positions: &state.positions,
            predicted: &ws.predicted,
            h,
            params: &self.params,
        };
        for o in obstacles.iter_mut() {
            o.advance(t_end);
            o.detect(&input, &mut ws.contacts);
        }
        let pinned = &self.pinned;
        ws.contacts.retain(|c| !pinned[c.vertex as usize]);
        // Stable: contacts of one vertex stay in obstacle order.
        ws.contacts.sort_by_key(|c| c.vertex);
        ws.impulses.clear();
        ws.impulses.resize(ws.contacts.len(), Vec3::zeros());
        ws.in_contact.iter_mut().for_each(|c| *c = false);
        for c in &ws.contacts {
            ws.in_contact[c.vertex as usize] = true;
        }
        ws.self_contacts.clear();
        ws.self_nodes.clear();
        if let Some(detector) = &mut self.self_contact {
            detector.detect(
                &state.positions,
                &ws.predicted,
                h,
                &self.params,
                &mut ws.self_contacts,
            );
            ws.self_contacts.retain(|c| {
                !(pinned[c.vertex as usize] && c.triangle.iter().all(|&i| pinned[i as usize]))
            });
            for c in &ws.self_contacts {
                let nodes = std::iter::once(c.vertex).chain(c.triangle);
                ws.self_nodes.extend(nodes.filter(|&j| !pinned[j as usize]));
            }
            ws.self_nodes.sort_unstable();
            ws.self_nodes.dedup();
            for &j in &ws.self_nodes {
                ws.in_contact[j as usize] = true;
            }
        }
        ws.self_impulses.clear();
        ws.self_impulses
            .resize(ws.self_contacts.len(), Vec3::zeros());
        self.times.detect += started.elapsed();
    }

    /// Air damping of the carried velocity: v* <- v / (1 + alpha h) + h g, off at contact and
    /// pinned nodes.
    fn damp(&mut self, h: f64) {
        let alpha = self.params.air_damping;
        if alpha == 0.0 {
            return;
        }
        // Damp the velocity carried over from the last step, not this step's gravity impulse:
        // damping v* = v + h g as a whole would weaken gravity by 1 / (1 + alpha h) at rest
        // (found by the hanging-sheet scenario: a sheet 12% too short with alpha = 8 /s).
        let factor = 1.0 / (1.0 + alpha * h);
        let gravity = Vec3::new(0.0, -self.params.gravity * h, 0.0);
        for i in 0..self.ws.v_star.len() {
            if !self.ws.in_contact[i] && !self.pinned[i] {
                self.ws.v_star[i] = (self.ws.v_star[i] - gravity) * factor + gravity;
            }
        }
    }

    fn iterate(&mut self, state: &ClothState, substeps: usize, h: f64) -> StepReport {
        let n = state.positions.len();
        let mut report = StepReport {
            contacts: self.ws.contacts.len(),
            self_contacts: self.ws.self_contacts.len(),
            ..StepReport::default()
        };
        for c in &self.ws.contacts {
            let depth = -c.distance;
            report.max_depth = report.max_depth.max(depth);
            if depth > self.params.contact_tolerance {
                report.deep_contacts += 1;
            }
        }
        let started = Instant::now();
        {
            let constraints = &self.constraints;
            let x = &state.positions;
            self.ws
                .ax_start
                .par_chunks_mut(2048)
                .enumerate()
                .for_each(|(chunk, out)| {
                    for (k, ax) in out.iter_mut().enumerate() {
                        *ax = constraints.apply(chunk * 2048 + k, x);
                    }
                });
        }
        self.ws.v.copy_from_slice(&self.ws.v_star);
        self.times.local += started.elapsed();
        let started = Instant::now();
        self.effective_masses(substeps);
        {
            let ws = &mut self.ws;
            let (node_mass, pinned) = (&ws.node_mass, &self.pinned);
            let inverse = |j: u32| {
                if pinned[j as usize] {
                    0.0
                } else {
                    1.0 / node_mass[j as usize]
                }
            };
            ws.self_mass.clear();
            ws.self_mass.extend(ws.self_contacts.iter().map(|c| {
                let other: f64 = c
                    .triangle
                    .iter()
                    .zip(c.weights)
                    .map(|(&i, w)| w * w * inverse(i))
                    .sum();
                1.0 / (inverse(c.vertex) + other)
            }));
        }
        self.times.contact += started.elapsed();

        let limit = if self.ws.self_contacts.is_empty() {
            self.params.max_iterations
        } else {
            CROSSING_ITERATION_FACTOR * self.params.max_iterations
        };
        for iteration in 1..=limit {
            let lag = self.systems[&substeps].lags_bending();
            self.local_step(state, h, lag);
            self.contact_step(substeps);
            if !self.ws.self_contacts.is_empty() {
                self.self_contact_step(substeps);
            }
            let started = Instant::now();
            for i in 0..n {
                if self.pinned[i] {
                    self.ws.rhs[i] = self.ws.v_star[i];
                }
            }
            let system = self.systems.get_mut(&substeps).expect("system factorized");
            system.solve(&self.ws.rhs, &mut self.ws.v_next);
            self.times.solve += started.elapsed();

            let started = Instant::now();
            let ws = &self.ws;
            let mut residual =
                ws.v.iter()
                    .zip(&ws.v_next)
                    .map(|(a, b)| (a - b).amax())
                    .fold(0.0, f64::max);
            for ((c, r), m) in ws.contacts.iter().zip(&ws.impulses).zip(&ws.effective_mass) {
                residual = residual.max(c.alart_curnier(*r, ws.v_next[c.vertex as usize], *m));
            }
            for ((c, r), m) in ws
                .self_contacts
                .iter()
                .zip(&ws.self_impulses)
                .zip(&ws.self_mass)
            {
                let w = ws.v_next[c.vertex as usize] - c.point(&ws.v_next);
                let ac = alart_curnier(c.normal, c.min_normal_velocity, c.friction, *r, w, *m);
                residual = residual.max(ac);
            }
            std::mem::swap(&mut self.ws.v, &mut self.ws.v_next);
            self.times.contact += started.elapsed();
            report.iterations = iteration;
            report.residual = residual;
            if residual < self.params.tolerance {
                break;
            }
            if iteration >= self.params.max_iterations && !self.layers_would_cross(h) {
                break;
            }
        }
        report
    }

    /// Whether the current velocities carry a vertex through the triangle of one of its pairs
    /// by the end of the step (a pair on the right side now, on the wrong side then).
    fn layers_would_cross(&self, h: f64) -> bool {
        let ws = &self.ws;
        ws.self_contacts
            .iter()
            .filter(|c| c.distance > 0.0)
            .any(|c| {
                let approach = (ws.v[c.vertex as usize] - c.point(&ws.v)).dot(&c.normal);
                c.distance + h * approach < 0.0
            })
    }

    /// Effective mass of every contact node (body contacts and cloth pairs): m_j / u_j with
    /// u = P^-1 (M 1_C), the velocity node j gets when every contact node j receives an
    /// impulse of its own mass m_j (one extra solve per step). Inside a patch in contact this
    /// is m_j (P 1 = M 1: the patch moves as one, Ly et al.'s choice, exact for a rigid
    /// impact); for an isolated contact it is 1 / (P^-1)_jj, the exact response of the node
    /// held by its free neighbours. See `contact_step`.
    fn effective_masses(&mut self, substeps: usize) {
        let ws = &mut self.ws;
        ws.effective_mass.clear();
        if ws.contacts.is_empty() && ws.self_nodes.is_empty() {
            return;
        }
        for ((b, &m), &c) in ws
            .patch_load
            .iter_mut()
            .zip(&self.masses)
            .zip(&ws.in_contact)
        {
            *b = if c { m } else { 0.0 };
        }
        let system = self.systems.get_mut(&substeps).expect("system factorized");
        system.solve_scalar(&ws.patch_load, &mut ws.patch_response);
        let masses = &self.masses;
        let response = &ws.patch_response;
        let mass = |j: usize| masses[j] / response[j].clamp(MIN_PATCH_RESPONSE, 1.0);
        ws.effective_mass
            .extend(ws.contacts.iter().map(|c| mass(c.vertex as usize)));
        for &j in &ws.self_nodes {
            ws.node_mass[j as usize] = mass(j as usize);
        }
    }

    /// Projections at x = x_n + h v and the right-hand side M v* + h sum w A^T (p - A x_n),
    /// gathered per vertex (no write conflicts, same result for any thread count).
    fn local_step(&mut self, state: &ClothState, h: f64, lag_bending: bool) {
        let started = Instant::now();
        let ws = &mut self.ws;
        for ((p, x), v) in ws.positions.iter_mut().zip(&state.positions).zip(&ws.v) {
            *p = x + h * v;
        }
        let inputs = ProjectionInputs {
            seam_length_cap: self.seam_length_cap,
            attachment_targets: &self.attachment_targets,
        };
        let constraints = &self.constraints;
        let positions = &ws.positions;
        let ax_start = &ws.ax_start;
        ws.q.par_chunks_mut(2048)
            .enumerate()
            .for_each(|(chunk, out)| {
                for (k, q) in out.iter_mut().enumerate() {
                    let t = chunk * 2048 + k;
                    let ax = constraints.apply(t, positions);
                    // Lagged bending enters at the current iterate (see system.rs).
                    let base = if lag_bending && constraints.is_bending(t) {
                        ax
                    } else {
                        ax_start[t]
                    };
                    *q = constraints.project(t, ax, &inputs) - base;
                }
            });
        let q = &ws.q;
        let (ptr, inc) = (&self.incidence_ptr, &self.incidence);
        let (masses, v_star) = (&self.masses, &ws.v_star);
        ws.rhs
            .par_chunks_mut(1024)
            .enumerate()
            .for_each(|(chunk, out)| {
                for (k, rhs) in out.iter_mut().enumerate() {
                    let i = chunk * 1024 + k;
                    let mut sum = Vec3::zeros();
                    for &(t, cw) in &inc[ptr[i]..ptr[i + 1]] {
                        sum += cw * q[t as usize];
                    }
                    *rhs = masses[i] * v_star[i] + h * sum;
                }
            });
        self.times.local += started.elapsed();
    }

    /// Per contact node: residual momentum f = rhs_j - ((P - m) v)_j, then each of its
    /// contacts' impulse in turn (Gauss-Seidel over a node's obstacles) for a node of
    /// effective mass m, added to rhs_j.
    ///
    /// Ly et al. take m = m_j, the node's own mass. The fixed point does not depend on m,
    /// only the speed of the iteration does: the impulse is m times the velocity correction,
    /// while the global solve moves the node by (P^-1)_jj times the impulse. On light garment
    /// meshes the springs make P_jj 10^2-10^4 times m_j, so with m = m_j an isolated contact
    /// gets well under 1% of its correction per iteration (measured: residual ~1 m/s after 20
    /// iterations, cloth falling through the body), while m = P_jj overshoots wherever
    /// neighbouring nodes are in contact too and diverges. What the node really gets is the
    /// response of its whole contact patch: `effective_masses` takes m = m_j / (P^-1 M 1_C)_j,
    /// m_j inside a patch (Ly et al.'s choice, exact when the patch moves as one) and
    /// 1 / (P^-1)_jj for an isolated contact.
    fn contact_step(&mut self, substeps: usize) {
        let started = Instant::now();
        let system = &self.systems[&substeps];
        let ws = &mut self.ws;
        for (c, r) in ws.self_contacts.iter().zip(&ws.self_impulses) {
            apply_pair(&mut ws.rhs, c, *r);
        }
        let mut k = 0;
        while k < ws.contacts.len() {
            let j = ws.contacts[k].vertex as usize;
            let m = ws.effective_mass[k];
            let mut f = ws.rhs[j] - system.row_times(j, &ws.v) + m * ws.v[j];
            let mut total = Vec3::zeros();
            while k < ws.contacts.len() && ws.contacts[k].vertex as usize == j {
                // Under-relaxed: half-way from the last impulse to the new one.
                let r = ws.impulses[k]
                    + IMPULSE_RELAXATION * (ws.contacts[k].impulse(f, m) - ws.impulses[k]);
                ws.impulses[k] = r;
                f += r;
                total += r;
                k += 1;
            }
            ws.rhs[j] += total;
        }
        self.times.contact += started.elapsed();
    }

    /// Cloth-cloth pairs, after the body contacts: each pair is a contact of vertex p with
    /// the point B = sum_i w_i x_i of a triangle, solved on their relative motion with the
    /// reduced mass m_p m_B / (m_p + m_B) (1 / m_B = sum_i w_i^2 / m_i, pinned corners
    /// weigh nothing) and the same cone projection as body contacts; +r goes to p and -w_i r
    /// to the corners. Pairs are visited one after the other and each sees the impulses of
    /// those before it (Gauss-Seidel), so chains of stacked contacts converge; every pair's
    /// impulse is under-relaxed like a body contact's.
    ///
    /// Called with the right-hand side holding every pair's impulse from the last iteration
    /// (added by `contact_step` before the body contacts see it).
    fn self_contact_step(&mut self, substeps: usize) {
        let started = Instant::now();
        let system = &self.systems[&substeps];
        let ws = &mut self.ws;
        for &j in &ws.self_nodes {
            let j = j as usize;
            ws.node_free[j] = ws.node_mass[j] * ws.v[j] - system.row_times(j, &ws.v);
        }
        let pinned = &self.pinned;
        for k in 0..ws.self_contacts.len() {
            let c = ws.self_contacts[k];
            let old = ws.self_impulses[k];
            // Velocity of node j once the residual momentum acts on its effective mass,
            // without this pair's impulse `share` (pinned nodes keep their velocity).
            let free_velocity = |j: u32, share: Vec3| {
                let j = j as usize;
                if pinned[j] {
                    ws.v[j]
                } else {
                    (ws.rhs[j] - share + ws.node_free[j]) / ws.node_mass[j]
                }
            };
            let mut point = Vec3::zeros();
            for (&i, w) in c.triangle.iter().zip(c.weights) {
                point += w * free_velocity(i, -w * old);
            }
            let mass = ws.self_mass[k];
            let relative = mass * (free_velocity(c.vertex, old) - point);
            let target = cone_impulse(c.normal, c.min_normal_velocity, c.friction, relative, mass);
            let new = old + IMPULSE_RELAXATION * (target - old);
            ws.self_impulses[k] = new;
            apply_pair(&mut ws.rhs, &c, new - old);
        }
        self.times.contact += started.elapsed();
    }
}

/// Adds a pair's impulse `r` to the right-hand side: +r at the vertex, -w_i r at the corners.
fn apply_pair(rhs: &mut [Vec3], c: &SelfContact, r: Vec3) {
    rhs[c.vertex as usize] += r;
    for (&i, w) in c.triangle.iter().zip(c.weights) {
        rhs[i as usize] -= w * r;
    }
}
