//! Analytic obstacles: a plane, a sphere and an oriented box, each optionally moving with a
//! constant acceleration (a kinematic prop such as an accelerating plate). The regression
//! suite and the drape bench use the plane (ground, incline, accelerating plate) and the
//! sphere; the box is for library users' scenes (a table, a bench) in `Obstacles::props`,
//! checked by its tests here.

use nalgebra::Rotation3;

use super::{Obstacle, SurfacePoint};
use crate::cloth::Vec3;

/// Prescribed motion of a rigid prop: offset(t) = v0 t + a t^2 / 2 (no rotation).
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct Kinematic {
    /// Initial velocity, m/s.
    pub velocity: Vec3,
    /// Constant acceleration, m/s^2.
    pub acceleration: Vec3,
}

impl Kinematic {
    fn offset(&self, t: f64) -> Vec3 {
        self.velocity * t + 0.5 * t * t * self.acceleration
    }
    fn velocity_at(&self, t: f64) -> Vec3 {
        self.velocity + self.acceleration * t
    }
}

/// An infinite plane (the ground of every scene; the regression suite's incline and
/// accelerating plate).
#[derive(Debug, Clone, PartialEq)]
pub struct Plane {
    /// A point on the plane at t = 0, m.
    pub point: Vec3,
    /// Unit normal (the free side).
    pub normal: Vec3,
    /// Friction coefficient.
    pub friction: f64,
    /// Motion.
    pub motion: Kinematic,
    time: f64,
}

impl Plane {
    /// A static plane through `point` with normal `normal` (normalized here).
    pub fn new(point: Vec3, normal: Vec3, friction: f64) -> Self {
        Self {
            point,
            normal: normal.normalize(),
            friction,
            motion: Kinematic::default(),
            time: 0.0,
        }
    }

    /// The ground y = `height`.
    pub fn ground(height: f64, friction: f64) -> Self {
        Self::new(Vec3::new(0.0, height, 0.0), Vec3::y(), friction)
    }
}

impl Obstacle for Plane {
    fn friction(&self) -> f64 {
        self.friction
    }
    fn advance(&mut self, time: f64) {
        self.time = time;
    }
    fn surface_point(&self, p: Vec3, _max_distance: f64) -> Option<SurfacePoint> {
        let origin = self.point + self.motion.offset(self.time);
        Some(SurfacePoint {
            distance: (p - origin).dot(&self.normal),
            normal: self.normal,
            velocity: self.motion.velocity_at(self.time),
        })
    }
}

/// A sphere (the drape bench's and the regression suite's obstacle).
#[derive(Debug, Clone, PartialEq)]
pub struct Sphere {
    /// Centre at t = 0, m.
    pub center: Vec3,
    /// Radius, m.
    pub radius: f64,
    /// Friction coefficient.
    pub friction: f64,
    /// Motion.
    pub motion: Kinematic,
    time: f64,
}

impl Sphere {
    /// A static sphere.
    pub fn new(center: Vec3, radius: f64, friction: f64) -> Self {
        Self {
            center,
            radius,
            friction,
            motion: Kinematic::default(),
            time: 0.0,
        }
    }
}

impl Obstacle for Sphere {
    fn friction(&self) -> f64 {
        self.friction
    }
    fn advance(&mut self, time: f64) {
        self.time = time;
    }
    fn surface_point(&self, p: Vec3, max_distance: f64) -> Option<SurfacePoint> {
        let d = p - (self.center + self.motion.offset(self.time));
        let r = d.norm();
        let distance = r - self.radius;
        if distance > max_distance {
            return None;
        }
        let normal = if r > 1e-12 { d / r } else { Vec3::y() };
        Some(SurfacePoint {
            distance,
            normal,
            velocity: self.motion.velocity_at(self.time),
        })
    }
}

/// An oriented box: a prop for library users' scenes (no command or scenario uses it yet).
#[derive(Debug, Clone, PartialEq)]
pub struct Cuboid {
    /// Centre at t = 0, m.
    pub center: Vec3,
    /// Half extents along the box's own axes, m.
    pub half_extents: Vec3,
    /// Orientation (box axes to world).
    pub rotation: Rotation3<f64>,
    /// Friction coefficient.
    pub friction: f64,
    /// Motion.
    pub motion: Kinematic,
    time: f64,
}

impl Cuboid {
    /// A static box.
    pub fn new(center: Vec3, half_extents: Vec3, rotation: Rotation3<f64>, friction: f64) -> Self {
        Self {
            center,
            half_extents,
            rotation,
            friction,
            motion: Kinematic::default(),
            time: 0.0,
        }
    }
}

impl Obstacle for Cuboid {
    fn friction(&self) -> f64 {
        self.friction
    }
    fn advance(&mut self, time: f64) {
        self.time = time;
    }
    fn surface_point(&self, p: Vec3, max_distance: f64) -> Option<SurfacePoint> {
        let local = self.rotation.inverse() * (p - self.center - self.motion.offset(self.time));
        let e = self.half_extents;
        let q = local.abs() - e;
        let outside = Vec3::new(q.x.max(0.0), q.y.max(0.0), q.z.max(0.0));
        let (distance, normal_local) = if outside.norm() > 0.0 {
            // Outside: the normal points from the closest box point to p.
            let closest = Vec3::new(
                local.x.clamp(-e.x, e.x),
                local.y.clamp(-e.y, e.y),
                local.z.clamp(-e.z, e.z),
            );
            let d = local - closest;
            (d.norm(), d / d.norm())
        } else {
            // Inside: the nearest face.
            let axis = (0..3)
                .max_by(|&a, &b| q[a].total_cmp(&q[b]))
                .expect("three axes");
            let mut n = Vec3::zeros();
            n[axis] = local[axis].signum().max(0.0) * 2.0 - 1.0;
            (q[axis], n)
        };
        if distance > max_distance {
            return None;
        }
        Some(SurfacePoint {
            distance,
            normal: self.rotation * normal_local,
            velocity: self.motion.velocity_at(self.time),
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn signed_distances() {
        let s = Sphere::new(Vec3::zeros(), 1.0, 0.0);
        let q = s.surface_point(Vec3::new(0.0, 0.5, 0.0), 0.1).unwrap();
        assert!((q.distance + 0.5).abs() < 1e-15 && q.normal == Vec3::y());
        assert!(s.surface_point(Vec3::new(0.0, 2.0, 0.0), 0.1).is_none());

        let b = Cuboid::new(
            Vec3::zeros(),
            Vec3::new(1.0, 0.5, 2.0),
            Rotation3::identity(),
            0.0,
        );
        let q = b.surface_point(Vec3::new(0.2, 0.4, 0.0), 1.0).unwrap();
        assert!((q.distance + 0.1).abs() < 1e-15, "{q:?}");
        assert_eq!(q.normal, Vec3::y());
        let q = b.surface_point(Vec3::new(0.0, -0.8, 0.0), 1.0).unwrap();
        assert!((q.distance - 0.3).abs() < 1e-15 && q.normal == -Vec3::y());
        let q = b.surface_point(Vec3::new(2.0, 1.5, 0.0), 5.0).unwrap();
        assert!((q.distance - 2f64.sqrt()).abs() < 1e-15);

        let mut plate = Plane::ground(0.0, 0.3);
        plate.motion.acceleration = Vec3::new(2.0, 0.0, 0.0);
        plate.advance(0.5);
        let q = plate.surface_point(Vec3::new(0.0, 0.1, 0.0), 0.0).unwrap();
        assert!((q.distance - 0.1).abs() < 1e-15);
        assert_eq!(q.velocity, Vec3::new(1.0, 0.0, 0.0));
    }
}
