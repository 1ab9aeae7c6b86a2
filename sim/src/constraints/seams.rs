//! Seams: zero-rest-length springs between vertex pairs that sew panels together. The pull is
//! ramped without touching the factorized matrix: the projection keeps a fraction `opening`
//! of the current gap, so the effective stiffness is w (1 - opening), from 0 (opening 1) to
//! the full w (opening 0).

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
pub(super) fn project(gap: Vec3, opening: f64) -> Vec3 {
    gap * opening.clamp(0.0, 1.0)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn opening_scales_the_kept_gap() {
        let gap = Vec3::new(0.1, -0.2, 0.3);
        assert_eq!(project(gap, 1.0), gap);
        assert_eq!(project(gap, 0.0), Vec3::zeros());
        assert!((project(gap, 0.25) - gap * 0.25).norm() < 1e-15);
    }
}
