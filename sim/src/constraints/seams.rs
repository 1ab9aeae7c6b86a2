//! Seams: springs between vertex pairs that sew panels together. Their pull is ramped without
//! touching the factorized matrix: the projection caps the gap at a length (the same for all
//! seams, lowered frame by frame to 0), so a seam is slack while its gap is under the cap and
//! closes no faster than the cap shrinks. With the cap at 0 a seam is a zero-length spring.

use serde::{Deserialize, Serialize};

use super::{Constraints, Kind};
use crate::cloth::Vec3;

/// A seam spring between two vertices.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct Seam {
    /// First vertex.
    pub a: u32,
    /// Second vertex.
    pub b: u32,
    /// Stiffness, N/m.
    pub stiffness: f64,
}

pub(super) fn add(c: &mut Constraints, seams: &[Seam]) {
    for s in seams {
        c.push(&[(s.a, 1.0), (s.b, -1.0)], s.stiffness, Kind::Seam);
    }
}

#[inline]
pub(super) fn project(gap: Vec3, cap: f64) -> Vec3 {
    let length = gap.norm();
    if length > cap.max(0.0) {
        gap * (cap.max(0.0) / length)
    } else {
        gap
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_cap_limits_the_kept_gap() {
        let gap = Vec3::new(0.0, 0.3, 0.4);
        assert_eq!(project(gap, f64::INFINITY), gap);
        assert_eq!(project(gap, 1.0), gap);
        assert_eq!(project(gap, 0.0), Vec3::zeros());
        assert!((project(gap, 0.25) - gap * 0.5).norm() < 1e-15);
    }
}
