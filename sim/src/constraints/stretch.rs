//! Edge springs: one term per edge, A x = x_i - x_j, projected to the rest length.
//! Energy (k_s / 2)(|x_i - x_j| - L0)^2 with k_s in N/m.

use super::{Constraints, Kind};
use crate::cloth::{ClothMesh, Vec3};

/// Adds the edge springs, which must be the first terms (see `Constraints::project_all`).
pub(super) fn add(c: &mut Constraints, mesh: &ClothMesh, stiffness: f64) {
    assert!(c.is_empty(), "edge springs come first");
    let rest = mesh.rest();
    for &[i, j] in mesh.edges() {
        let rest_length = (rest[i as usize] - rest[j as usize]).norm();
        c.push(
            &[(i, 1.0), (j, -1.0)],
            stiffness,
            Kind::Stretch { rest_length },
        );
        c.edge_rest.push(rest_length);
    }
    c.edges = c.len();
}

/// The edge vector with its direction kept and its length set to the rest length.
#[inline]
pub(super) fn project(edge: Vec3, rest_length: f64) -> Vec3 {
    let length = edge.norm();
    if length > 1e-14 {
        edge * (rest_length / length)
    } else {
        Vec3::zeros()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn projection_restores_rest_length_and_direction() {
        let p = project(Vec3::new(3.0, 0.0, 4.0), 2.0);
        assert!((p.norm() - 2.0).abs() < 1e-15);
        assert!((p.normalize() - Vec3::new(0.6, 0.0, 0.8)).norm() < 1e-15);
        assert_eq!(project(Vec3::zeros(), 1.0), Vec3::zeros());
    }
}
