//! Extra springs between any two vertices with their own rest length and stiffness (tethers,
//! chains of small panels); projected like edge springs.

use serde::{Deserialize, Serialize};

use super::{Constraints, Kind};

/// A spring between two vertices.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct Spring {
    /// First vertex.
    pub a: u32,
    /// Second vertex.
    pub b: u32,
    /// Rest length, m.
    pub rest_length: f64,
    /// Stiffness, N/m.
    pub stiffness: f64,
}

pub(super) fn add(c: &mut Constraints, springs: &[Spring]) {
    for s in springs {
        c.push(
            &[(s.a, 1.0), (s.b, -1.0)],
            s.stiffness,
            Kind::Stretch {
                rest_length: s.rest_length,
            },
        );
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::cloth::Vec3;

    #[test]
    fn a_spring_is_an_edge_term_with_its_own_rest_length() {
        let mut c = Constraints::default();
        c.ptr.push(0);
        add(
            &mut c,
            &[Spring {
                a: 0,
                b: 1,
                rest_length: 0.5,
                stiffness: 7.0,
            }],
        );
        assert_eq!(c.len(), 1);
        assert_eq!(c.weight(0), 7.0);
        let x = [Vec3::zeros(), Vec3::new(2.0, 0.0, 0.0)];
        let ax = c.apply(0, &x);
        let inputs = super::super::ProjectionInputs {
            seam_length_cap: f64::INFINITY,
            attachment_targets: &[],
        };
        assert!((c.project(0, ax, &inputs).norm() - 0.5).abs() < 1e-15);
    }
}
