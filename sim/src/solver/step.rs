//! One step as named stages, each timed by `Solver::timed`: predict, detect, damp, prepare
//! the contacts, then the iteration (local projections, body contacts, cloth-cloth contacts,
//! global solve, residual) until it converges, and finish.

use super::{CROSSING_ITERATION_FACTOR, Solver, Stage, StepReport};
use crate::cloth::{ClothState, Vec3};
use crate::constraints::ProjectionInputs;
use crate::contact::alart_curnier;
use crate::error::Result;
use crate::obstacles::{DetectionInput, Obstacles};

impl Solver {
    /// One step of length frame_dt / `substeps` ending at time `t_end` (the global matrix for
    /// `substeps` is factorized first if it is not yet).
    pub fn step(
        &mut self,
        state: &mut ClothState,
        obstacles: &mut Obstacles,
        substeps: usize,
        t_end: f64,
    ) -> Result<StepReport> {
        self.system_for(substeps)?;
        let h = self.frame_dt / substeps as f64;
        self.timed(Stage::Predict, |s| s.predict(state, h));
        self.timed(Stage::Refit, |_| {
            obstacles.each_mut().for_each(|o| o.advance(t_end))
        });
        self.timed(Stage::Detect, |s| s.detect(state, obstacles, h));
        self.timed(Stage::SelfDetect, |s| s.self_detect(state, h));
        self.timed(Stage::Damp, |s| s.damp(h));
        let mut report = self.timed(Stage::Prepare, |s| s.prepare_contacts(state, substeps));
        let limit = if self.ws.self_contacts.is_empty() {
            self.params.max_iterations
        } else {
            CROSSING_ITERATION_FACTOR * self.params.max_iterations
        };
        if let Some(a) = &mut self.anderson {
            a.reset();
        }
        for iteration in 1..=limit {
            self.timed(Stage::Accelerate, |s| {
                if let Some(a) = &mut s.anderson {
                    a.begin(&s.ws);
                }
            });
            let lag = self.systems[&substeps].lags_bending();
            self.timed(Stage::Local, |s| s.local_step(state, h, lag));
            self.timed(Stage::Contact, |s| s.contact_step(substeps));
            if !self.ws.self_contacts.is_empty() {
                self.timed(Stage::SelfContact, |s| s.self_contact_step(substeps));
            }
            self.timed(Stage::Solve, |s| s.global_solve(substeps));
            // Before the last planned iteration only "below the tolerance or not" matters;
            // the residual a step reports is its last iteration's, computed in full.
            let enough = if iteration < self.params.max_iterations {
                self.params.tolerance
            } else {
                f64::INFINITY
            };
            let residual = self.timed(Stage::Residual, |s| s.residual(enough));
            report.iterations = iteration;
            report.residual = residual;
            if residual < self.params.tolerance {
                break;
            }
            if iteration >= self.params.max_iterations && !self.layers_would_cross(h) {
                break;
            }
            self.timed(Stage::Accelerate, |s| {
                if let Some(a) = &mut s.anderson {
                    a.accelerate(&mut s.ws);
                }
            });
        }
        self.timed(Stage::Finish, |s| s.finish(state, h));
        Ok(report)
    }

    fn predict(&mut self, state: &ClothState, h: f64) {
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
    }

    /// Body and prop contacts of the predicted positions, sorted by vertex.
    fn detect(&mut self, state: &ClothState, obstacles: &mut Obstacles, h: f64) {
        let ws = &mut self.ws;
        ws.contacts.clear();
        let input = DetectionInput {
            positions: &state.positions,
            predicted: &ws.predicted,
            h,
            params: &self.params,
        };
        for o in obstacles.each_mut() {
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
    }

    /// Cloth-cloth pairs of the step and their nodes (marked in contact, after `detect`).
    fn self_detect(&mut self, state: &ClothState, h: f64) {
        let ws = &mut self.ws;
        let pinned = &self.pinned;
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

    /// What the iteration starts from: the step's contact counts and depths, A x_n of every
    /// term, v = v*, and the effective masses of the contact nodes and pairs.
    fn prepare_contacts(&mut self, state: &ClothState, substeps: usize) -> StepReport {
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
        self.constraints
            .apply_all(&state.positions, &mut self.ws.ax_start);
        self.ws.v.copy_from_slice(&self.ws.v_star);
        self.effective_masses(substeps);
        self.pair_masses();
        report
    }

    /// Projections at x = x_n + h v and the right-hand side M v* + h sum w A^T (p - A x_n),
    /// gathered per vertex (no write conflicts, same result for any thread count).
    fn local_step(&mut self, state: &ClothState, h: f64, lag_bending: bool) {
        let ws = &mut self.ws;
        for ((p, x), v) in ws.positions.iter_mut().zip(&state.positions).zip(&ws.v) {
            *p = x + h * v;
        }
        let inputs = ProjectionInputs {
            seam_length_cap: self.seam_length_cap,
            attachment_targets: &self.attachment_targets,
        };
        self.constraints
            .project_all(&ws.positions, &ws.ax_start, lag_bending, &inputs, &mut ws.q);
        let q = &ws.q;
        let (ptr, inc) = (&self.incidence_ptr, &self.incidence);
        let (masses, v_star) = (&self.masses, &ws.v_star);
        crate::spin_join::halves(&mut ws.rhs, ptr, |first, out| {
            for (k, rhs) in out.iter_mut().enumerate() {
                let i = first + k;
                let mut sum = Vec3::zeros();
                for &(t, cw) in &inc[ptr[i]..ptr[i + 1]] {
                    sum += cw * q[t as usize];
                }
                *rhs = masses[i] * v_star[i] + h * sum;
            }
        });
    }

    /// The global solve P v = rhs with the factorization for `substeps` (pinned vertices keep
    /// their prescribed velocity).
    fn global_solve(&mut self, substeps: usize) {
        for (i, &pinned) in self.pinned.iter().enumerate() {
            if pinned {
                self.ws.rhs[i] = self.ws.v_star[i];
            }
        }
        let system = self
            .systems
            .get_mut(&substeps)
            .expect("`step` factorized this substep count");
        system.solve(&self.ws.rhs, &mut self.ws.v_next);
    }

    /// The iteration's residual (largest velocity change, largest Alart-Curnier residual of
    /// a body contact or a cloth pair per unit mass), then the new velocities become current.
    /// The terms are visited in a fixed order, and as soon as the largest so far exceeds
    /// `enough` it is returned: a caller that only needs to know the residual is above its
    /// tolerance (the iteration goes on) skips the rest, which costs as much as a contact step.
    fn residual(&mut self, enough: f64) -> f64 {
        let ws = &self.ws;
        let velocities = ws.v.iter().zip(&ws.v_next).map(|(a, b)| (a - b).amax());
        let contacts = ws
            .contacts
            .iter()
            .zip(&ws.impulses)
            .zip(&ws.effective_mass)
            .map(|((c, r), m)| c.alart_curnier(*r, ws.v_next[c.vertex as usize], *m));
        let pairs = ws
            .self_contacts
            .iter()
            .zip(&ws.self_impulses)
            .zip(&ws.self_mass)
            .map(|((c, r), m)| {
                let w = ws.v_next[c.vertex as usize] - c.point(&ws.v_next);
                alart_curnier(c.normal, c.min_normal_velocity, c.friction, *r, w, *m)
            });
        let residual = velocities
            .chain(contacts)
            .chain(pairs)
            .try_fold(0.0, |largest: f64, term| {
                let largest = largest.max(term);
                if largest > enough {
                    Err(largest)
                } else {
                    Ok(largest)
                }
            })
            .unwrap_or_else(|above| above);
        std::mem::swap(&mut self.ws.v, &mut self.ws.v_next);
        residual
    }

    /// x = x + h v with the step's final velocities.
    fn finish(&mut self, state: &mut ClothState, h: f64) {
        for ((x, v), v_new) in state
            .positions
            .iter_mut()
            .zip(state.velocities.iter_mut())
            .zip(&self.ws.v)
        {
            *v = *v_new;
            *x += h * v_new;
        }
    }
}
