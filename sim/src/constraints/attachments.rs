//! Attachments: a vertex pulled toward a moving target point (a point on the body, given by the
//! scene every substep). A x = x_i, projected onto the target.

use serde::{Deserialize, Serialize};

use super::{Constraints, Kind};
use crate::cloth::Vec3;

/// A spring from a cloth vertex to a target point that the scene moves.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct Attachment {
    /// Cloth vertex.
    pub vertex: u32,
    /// Stiffness, N/m.
    pub stiffness: f64,
}

pub(super) fn add(c: &mut Constraints, attachments: &[Attachment]) {
    for (k, a) in attachments.iter().enumerate() {
        c.push(&[(a.vertex, 1.0)], a.stiffness, Kind::Attach { target: k });
    }
}

#[inline]
pub(super) fn project(target: Vec3) -> Vec3 {
    target
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn projection_is_the_target() {
        let t = Vec3::new(1.0, 2.0, 3.0);
        assert_eq!(project(t), t);
    }
}
