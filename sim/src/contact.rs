//! Contacts and their exact Signorini-Coulomb solve, independent of what produced them (an
//! obstacle, or a triangle of the same cloth: see `self_contact.rs`).
//!
//! A contact constrains one cloth node's velocity v relative to the obstacle's velocity u at
//! the contact point: (v - u).n >= g (g > 0 pushes a node that is too close or inside back
//! out), and the impulse r lies in the Coulomb cone |r_t| <= mu r_n. Given the node's residual
//! momentum f (everything in its row of the global system except its own mass term), the node
//! either takes off (r = 0), sticks (relative velocity zero) or slides (r_t on the cone's rim).

use crate::cloth::Vec3;
use crate::params::SolverParams;

/// One contact of a cloth vertex with an obstacle.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Contact {
    /// Cloth vertex.
    pub vertex: u32,
    /// Unit normal at the contact point, pointing out of the obstacle.
    pub normal: Vec3,
    /// Obstacle velocity at the contact point, m/s.
    pub velocity: Vec3,
    /// Lower bound g on the relative normal velocity (v - u).n, m/s.
    pub min_normal_velocity: f64,
    /// Coulomb friction coefficient.
    pub friction: f64,
    /// Signed distance of the vertex's current position to the obstacle surface at the end of
    /// the step (negative inside), m.
    pub distance: f64,
}

impl Contact {
    /// Builds a contact from a query at the predicted position x~ = x + h v*: `distance` is
    /// the signed distance of x~, `normal` the outward normal there. The constraint keeps the
    /// node `offset` away from the surface at the end of the step (linearized at x~); a node
    /// found inside is brought out no faster than `max_push_out_speed` relative to the surface.
    #[allow(clippy::too_many_arguments)]
    pub fn from_query(
        vertex: u32,
        predicted_distance: f64,
        normal: Vec3,
        velocity: Vec3,
        predicted_motion: Vec3,
        h: f64,
        friction: f64,
        params: &SolverParams,
    ) -> Self {
        // Signed distance of the current position, linearized: d_n = d~ - n.(x~ - x).
        let current = predicted_distance - normal.dot(&predicted_motion);
        let needed = (params.contact_offset - current) / h - normal.dot(&velocity);
        Self {
            vertex,
            normal,
            velocity,
            min_normal_velocity: needed.min(params.max_push_out_speed),
            friction,
            distance: current,
        }
    }

    /// The contact impulse (kg m/s) for a node of `mass` whose residual momentum is `f`.
    #[inline]
    pub fn impulse(&self, f: Vec3, mass: f64) -> Vec3 {
        cone_impulse(
            self.normal,
            self.min_normal_velocity,
            self.friction,
            f - mass * self.velocity,
            mass,
        )
    }

    /// Alart-Curnier residual of impulse `r` and node velocity `v`, divided by the mass (m/s):
    /// zero exactly when (r, v) satisfy Signorini's condition and Coulomb's law.
    pub fn alart_curnier(&self, r: Vec3, v: Vec3, mass: f64) -> f64 {
        alart_curnier(
            self.normal,
            self.min_normal_velocity,
            self.friction,
            r,
            v - self.velocity,
            mass,
        )
    }
}

/// The impulse r of a contact with unit `normal`, bound g on the normal velocity and Coulomb
/// coefficient `mu`, for a node of `mass` whose momentum relative to the obstacle is `local`
/// (f - m u): take-off (r = 0), stick (velocity (local + r) / m = 0 tangentially and g along
/// n) or slide (r_t on the rim of the cone). Body contacts and cloth-cloth pairs (with their
/// reduced mass and relative momentum) share it.
#[inline]
pub(crate) fn cone_impulse(normal: Vec3, g: f64, mu: f64, local: Vec3, mass: f64) -> Vec3 {
    let n = normal;
    let normal_part = local.dot(&n);
    let slack = normal_part - mass * g;
    if slack >= 0.0 {
        return Vec3::zeros(); // take-off
    }
    let r_n = -slack;
    let mut r_t = -(local - normal_part * n); // stick
    let limit = mu * r_n;
    let norm_t = r_t.norm();
    if norm_t > limit {
        r_t *= if norm_t > 0.0 { limit / norm_t } else { 0.0 }; // slide
    }
    r_n * n + r_t
}

/// Alart-Curnier residual (m/s) of impulse `r` and relative velocity `w` for the contact of
/// [`cone_impulse`].
pub(crate) fn alart_curnier(normal: Vec3, g: f64, mu: f64, r: Vec3, w: Vec3, mass: f64) -> f64 {
    let n = normal;
    let w_n = w.dot(&n) - g;
    let w_t = w - w.dot(&n) * n;
    let r_n = r.dot(&n);
    let r_t = r - r_n * n;
    let proj_n = (r_n - mass * w_n).max(0.0);
    let phi_n = r_n - proj_n;
    let trial = r_t - mass * w_t;
    let limit = mu * proj_n;
    let norm = trial.norm();
    let proj_t = if norm > limit && norm > 0.0 {
        trial * (limit / norm)
    } else {
        trial
    };
    let phi_t = r_t - proj_t;
    (phi_n * phi_n + phi_t.norm_squared()).sqrt() / mass
}

#[cfg(test)]
mod tests {
    use super::*;

    fn ground(friction: f64) -> Contact {
        Contact {
            vertex: 0,
            normal: Vec3::y(),
            velocity: Vec3::zeros(),
            min_normal_velocity: 0.0,
            friction,
            distance: 0.0,
        }
    }

    #[test]
    fn take_off_stick_and_slide() {
        let c = ground(0.5);
        let m = 2.0;
        // Moving away: no impulse, zero residual.
        let f = Vec3::new(0.3, 1.0, 0.0);
        assert_eq!(c.impulse(f, m), Vec3::zeros());
        assert!(c.alart_curnier(Vec3::zeros(), f / m, m) < 1e-15);
        // Pressing down with a small tangential push: sticks, velocity becomes zero.
        let f = Vec3::new(0.4, -1.0, 0.0);
        let r = c.impulse(f, m);
        let v = (f + r) / m;
        assert!(v.norm() < 1e-15, "stick leaves velocity {v:?}");
        assert!(c.alart_curnier(r, v, m) < 1e-15);
        // Large tangential push: slides with |r_t| = mu r_n, normal velocity zero.
        let f = Vec3::new(2.0, -1.0, 0.0);
        let r = c.impulse(f, m);
        assert!((r.y - 1.0).abs() < 1e-15);
        assert!((r.x + 0.5).abs() < 1e-15);
        let v = (f + r) / m;
        assert!(v.y.abs() < 1e-15 && v.x > 0.0);
        assert!(c.alart_curnier(r, v, m) < 1e-15);
        // A wrong impulse has a positive residual.
        assert!(c.alart_curnier(Vec3::zeros(), f / m, m) > 0.1);
    }

    #[test]
    fn friction_is_relative_to_the_obstacle() {
        let mut c = ground(1.0);
        c.velocity = Vec3::new(1.0, 0.0, 0.0);
        let m = 1.0;
        // A node at rest on a belt moving at 1 m/s and pressed down: sticks to the belt.
        let r = c.impulse(Vec3::new(0.0, -2.0, 0.0), m);
        let v = (Vec3::new(0.0, -2.0, 0.0) + r) / m;
        assert!((v - c.velocity).norm() < 1e-15, "{v:?}");
    }

    #[test]
    fn push_out_is_capped() {
        let params = SolverParams::default();
        let c = Contact::from_query(
            0,
            -0.05,
            Vec3::y(),
            Vec3::zeros(),
            Vec3::zeros(),
            0.01,
            0.3,
            &params,
        );
        assert_eq!(c.min_normal_velocity, params.max_push_out_speed);
        assert!(c.distance < 0.0);
        let resting = Contact::from_query(
            0,
            0.002,
            Vec3::y(),
            Vec3::zeros(),
            Vec3::zeros(),
            0.01,
            0.3,
            &params,
        );
        assert!((resting.min_normal_velocity - 0.1).abs() < 1e-12);
    }
}
