//! The contact stages of the iteration: effective masses of contact nodes and cloth pairs,
//! body contact impulses, cloth-cloth pair impulses, and the check that layers would cross.

use super::{IMPULSE_RELAXATION, MIN_PATCH_RESPONSE, Solver};
use crate::cloth::Vec3;
use crate::contact::cone_impulse;
use crate::self_contact::SelfContact;

impl Solver {
    /// Effective mass of every contact node (body contacts and cloth pairs): m_j / u_j with
    /// u = P^-1 (M 1_C), the velocity node j gets when every contact node j receives an
    /// impulse of its own mass m_j (one extra solve per step). Inside a patch in contact this
    /// is m_j (P 1 = M 1: the patch moves as one, Ly et al.'s choice, exact for a rigid
    /// impact); for an isolated contact it is 1 / (P^-1)_jj, the exact response of the node
    /// held by its free neighbours. See `contact_step`.
    pub(super) fn effective_masses(&mut self, substeps: usize) {
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

    /// Reduced mass of every cloth pair: 1 / (1 / m_p + sum_i w_i^2 / m_i), pinned nodes
    /// weighing nothing.
    pub(super) fn pair_masses(&mut self) {
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
    pub(super) fn contact_step(&mut self, substeps: usize) {
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
    pub(super) fn self_contact_step(&mut self, substeps: usize) {
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
    }

    /// Whether the current velocities carry a vertex through the triangle of one of its pairs
    /// by the end of the step (a pair on the right side now, on the wrong side then).
    pub(super) fn layers_would_cross(&self, h: f64) -> bool {
        let ws = &self.ws;
        ws.self_contacts
            .iter()
            .filter(|c| c.distance > 0.0)
            .any(|c| {
                let approach = (ws.v[c.vertex as usize] - c.point(&ws.v)).dot(&c.normal);
                c.distance + h * approach < 0.0
            })
    }
}

/// Adds a pair's impulse `r` to the right-hand side: +r at the vertex, -w_i r at the corners.
fn apply_pair(rhs: &mut [Vec3], c: &SelfContact, r: Vec3) {
    rhs[c.vertex as usize] += r;
    for (&i, w) in c.triangle.iter().zip(c.weights) {
        rhs[i as usize] -= w * r;
    }
}
