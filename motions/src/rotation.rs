//! Rotations in the forms SMPL data uses: axis-angle vectors (radians), 3x3 matrices acting on
//! column vectors, and unit quaternions for interpolation.

use nalgebra::{Matrix3, UnitQuaternion, Vector3};

/// Rodrigues' formula for an axis-angle vector `r` (angle = |r|), stable near zero: below
/// 1e-4 rad the sin/cos coefficients use their Taylor series (error < 1e-18).
pub fn axis_angle_to_matrix(r: [f64; 3]) -> Matrix3<f64> {
    let t2 = r[0] * r[0] + r[1] * r[1] + r[2] * r[2];
    let (a, b) = if t2 < 1e-8 {
        (
            1.0 - t2 / 6.0 + t2 * t2 / 120.0,
            0.5 - t2 / 24.0 + t2 * t2 / 720.0,
        )
    } else {
        let t = t2.sqrt();
        (t.sin() / t, (1.0 - t.cos()) / t2)
    };
    let k = Matrix3::new(0.0, -r[2], r[1], r[2], 0.0, -r[0], -r[1], r[0], 0.0);
    Matrix3::identity() + k * a + k * k * b
}

/// Unit quaternion of an axis-angle vector.
pub fn axis_angle_to_quat(r: [f64; 3]) -> UnitQuaternion<f64> {
    UnitQuaternion::from_scaled_axis(Vector3::from(r))
}

/// Axis-angle vector (angle in [0, pi]) of a unit quaternion.
pub fn quat_to_axis_angle(q: &UnitQuaternion<f64>) -> [f64; 3] {
    q.scaled_axis().into()
}

/// Spherical interpolation on the shorter arc: `b` is negated first if it lies in the other
/// hemisphere (q and -q are the same rotation, and mocap data flips between them).
pub fn slerp_shortest(
    a: &UnitQuaternion<f64>,
    b: &UnitQuaternion<f64>,
    t: f64,
) -> UnitQuaternion<f64> {
    let b = if a.coords.dot(&b.coords) < 0.0 {
        UnitQuaternion::new_unchecked(-b.into_inner())
    } else {
        *b
    };
    a.try_slerp(&b, t, 1e-12)
        .unwrap_or_else(|| UnitQuaternion::new_normalize(a.into_inner().lerp(&b.into_inner(), t)))
}

/// Interpolates two axis-angle vectors joint by joint (slerp, shorter arc).
pub fn slerp_axis_angle(a: [f64; 3], b: [f64; 3], t: f64) -> [f64; 3] {
    quat_to_axis_angle(&slerp_shortest(
        &axis_angle_to_quat(a),
        &axis_angle_to_quat(b),
        t,
    ))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn rodrigues_matches_quaternion_for_all_angle_ranges() {
        for r in [
            [0.0, 0.0, 0.0],
            [1e-9, -2e-9, 3e-9],
            [1e-5, 0.0, 0.0],
            [0.3, -1.2, 0.5],
            [0.0, std::f64::consts::PI, 0.0],
            [4.0, 1.0, -2.0],
        ] {
            let m = axis_angle_to_matrix(r);
            let q = axis_angle_to_quat(r).to_rotation_matrix().into_inner();
            let err = (m - q).abs().max();
            assert!(err < 1e-14, "r = {r:?}: |R - R_q| = {err:e}");
        }
    }

    #[test]
    fn slerp_takes_the_short_way_across_a_sign_flip() {
        let a = axis_angle_to_quat([0.0, 0.1, 0.0]);
        let b = UnitQuaternion::new_unchecked(-axis_angle_to_quat([0.0, 0.3, 0.0]).into_inner());
        let mid = quat_to_axis_angle(&slerp_shortest(&a, &b, 0.5));
        assert!((mid[1] - 0.2).abs() < 1e-12, "mid = {mid:?}");
    }
}
