//! Obstacles the cloth collides with: the animated body, a ground plane and static or
//! kinematic props. Each turns cloth positions into [`Contact`]s; the contact solve never
//! knows which obstacle a contact came from.

mod analytic;
mod body;
mod overlap;
mod trimesh;

pub use analytic::{Cuboid, Kinematic, Plane, Sphere};
pub use body::AnimatedMesh;
pub use overlap::{OVERLAP_REACH_M, Penetration, split_penetration};
pub use trimesh::{MeshSurface, StaticMesh};

use rayon::prelude::*;

use crate::cloth::Vec3;
use crate::contact::Contact;
use crate::params::SolverParams;

/// What an obstacle sees of the cloth when it looks for contacts.
#[derive(Debug, Clone, Copy)]
pub struct DetectionInput<'a> {
    /// Positions at the start of the step, m.
    pub positions: &'a [Vec3],
    /// Predicted positions x + h v* (inertia and gravity only), m.
    pub predicted: &'a [Vec3],
    /// Step length, s.
    pub h: f64,
    /// Solver settings (tolerance, offset, push-out speed).
    pub params: &'a SolverParams,
}

impl DetectionInput<'_> {
    /// The contact of vertex `i` with the surface point found for its predicted position, if
    /// that point is within the contact band.
    pub fn contact(&self, i: usize, s: &SurfacePoint, friction: f64) -> Option<Contact> {
        (s.distance < self.params.contact_tolerance).then(|| {
            Contact::from_query(
                i as u32,
                s.distance,
                s.normal,
                s.velocity,
                self.predicted[i] - self.positions[i],
                self.h,
                friction,
                self.params,
            )
        })
    }
}

/// Signed distance, outward normal and surface velocity of an obstacle at a point.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct SurfacePoint {
    /// Signed distance, m (negative inside).
    pub distance: f64,
    /// Unit normal pointing out of the obstacle.
    pub normal: Vec3,
    /// Velocity of the obstacle's surface at the closest point, m/s.
    pub velocity: Vec3,
}

/// Something cloth collides with.
pub trait Obstacle: Send + Sync {
    /// Coulomb friction coefficient against cloth.
    fn friction(&self) -> f64;
    /// Moves the obstacle to its pose at `time` (s), the end of the coming step.
    fn advance(&mut self, time: f64);
    /// The closest surface point to `p` if it is nearer than `max_distance` (inside points
    /// are always reported).
    fn surface_point(&self, p: Vec3, max_distance: f64) -> Option<SurfacePoint>;
    /// Appends the contacts of the step's cloth vertices to `out`, in vertex order.
    fn detect(&mut self, input: &DetectionInput, out: &mut Vec<Contact>) {
        detect_each(self, input, out);
    }
}

/// What a cloth collides with: the animated body, props (analytic shapes, static or kinematic
/// meshes) and the ground. Detection visits them in that order (body, props, ground), and a
/// vertex touching several is solved against them in that order.
#[derive(Default)]
pub struct Obstacles {
    /// The animated body.
    pub body: Option<AnimatedMesh>,
    /// Props, in detection order.
    pub props: Vec<Box<dyn Obstacle>>,
    /// The ground plane.
    pub ground: Option<Plane>,
}

impl Obstacles {
    /// The body alone.
    pub fn body(body: AnimatedMesh) -> Self {
        Self {
            body: Some(body),
            ..Self::default()
        }
    }

    /// The ground alone.
    pub fn ground(ground: Plane) -> Self {
        Self {
            ground: Some(ground),
            ..Self::default()
        }
    }

    /// These props alone, in detection order.
    pub fn props(props: Vec<Box<dyn Obstacle>>) -> Self {
        Self {
            props,
            ..Self::default()
        }
    }

    /// Every obstacle, in detection order.
    pub fn each_mut(&mut self) -> impl Iterator<Item = &mut dyn Obstacle> {
        let body = self.body.iter_mut().map(|b| b as &mut dyn Obstacle);
        let props = self
            .props
            .iter_mut()
            .map(|p| p.as_mut() as &mut dyn Obstacle);
        let ground = self.ground.iter_mut().map(|g| g as &mut dyn Obstacle);
        body.chain(props).chain(ground)
    }
}

/// Detection by one [`Obstacle::surface_point`] query per vertex, in parallel chunks
/// (concatenated in order, so the result does not depend on the thread count).
pub fn detect_each<O: Obstacle + ?Sized>(
    obstacle: &O,
    input: &DetectionInput,
    out: &mut Vec<Contact>,
) {
    let tolerance = input.params.contact_tolerance;
    let friction = obstacle.friction();
    let found: Vec<Vec<Contact>> = input
        .predicted
        .par_chunks(1024)
        .enumerate()
        .map(|(chunk, points)| {
            let mut local = Vec::new();
            for (k, &p) in points.iter().enumerate() {
                let i = chunk * 1024 + k;
                if let Some(s) = obstacle.surface_point(p, tolerance) {
                    local.extend(input.contact(i, &s, friction));
                }
            }
            local
        })
        .collect();
    out.extend(found.into_iter().flatten());
}
