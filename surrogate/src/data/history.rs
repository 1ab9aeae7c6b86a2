//! The body's longer past as a few numbers per frame: for each of [`HISTORY_SECONDS`], the
//! exponentially weighted mean of the past poses (that time constant) minus the current pose.
//!
//! Why: the pose window holds three frames (0.07 s at 30 fps) and the 8-frame window of arm a8
//! 0.27 s, while the hem of a loose dress swings with a period near 1.5 s. A weighted mean
//! summarizes the whole past at a fixed size, and it is a function of the body's motion
//! alone: unlike the garment's previous state (arms a19-a21) it cannot drift at prediction.
//! Every past pose is seen from the current frame's heading frame, as the window's are, so the
//! values do not depend on where the body walks or which way it faces.

use motions::Motion;

use super::conditions::{CONDITION_JOINTS, joint_6d};
use crate::error::Result;

/// The time constants of the history blocks, seconds.
pub const HISTORY_SECONDS: [f64; 3] = [0.1, 0.3, 1.0];

/// How many of the longest time constant the past is summed over: the weight left beyond is
/// e^-5 (0.7%) for it, less for the shorter ones.
const HORIZON: f64 = 5.0;

/// Values per time constant: the 22 joints' 6D rotations, then the root translation (m).
pub const HISTORY_VALUES: usize = CONDITION_JOINTS * 6 + 3;

/// For each time constant of [`HISTORY_SECONDS`], the [`HISTORY_VALUES`] values of the
/// weighted past minus the present: the 22 joints' 6D rotations (root orientation in frame
/// `t`'s heading frame), then the root translation relative to frame `t`'s in that frame.
/// Before the motion's first frame the body is taken to have stood in that frame's pose (as
/// the pose window does), so a body that never moved has a history of zeros.
pub fn pose_history(motion: &Motion, t: usize) -> Result<Vec<f64>> {
    let longest = HISTORY_SECONDS.iter().copied().fold(0.0, f64::max);
    let horizon = (HORIZON * longest * motion.fps).ceil();
    // Frames before the first are the first frame again: they are read once, and their
    // weights are summed in closed form, so a high frame rate costs no memory.
    let span = (t as f64).min(horizon) as usize;
    let window = motion.pose_window(t, span)?;
    let features: Vec<[f64; HISTORY_VALUES]> = window
        .poses
        .iter()
        .zip(&window.transl)
        .map(|(pose, transl)| {
            let mut f = [0.0; HISTORY_VALUES];
            for j in 0..CONDITION_JOINTS {
                f[6 * j..6 * j + 6].copy_from_slice(&joint_6d(pose, j));
            }
            f[CONDITION_JOINTS * 6..].copy_from_slice(transl);
            f
        })
        .collect();
    let now = features[span];
    let mut out = Vec::with_capacity(HISTORY_SECONDS.len() * HISTORY_VALUES);
    for tau in HISTORY_SECONDS {
        let rate = -1.0 / (tau * motion.fps);
        let q = rate.exp();
        // The weights of ages span + 1 ..= horizon, all on the first frame.
        let before_first =
            q.powf(span as f64 + 1.0) * -(rate * (horizon - span as f64)).exp_m1() / -rate.exp_m1();
        let mut mean = [0.0; HISTORY_VALUES];
        let mut total = 0.0;
        for (age, f) in features.iter().rev().enumerate() {
            let mut w = q.powi(age as i32);
            if age == span {
                w += before_first;
            }
            total += w;
            for (m, v) in mean.iter_mut().zip(f) {
                *m += w * v;
            }
        }
        out.extend(mean.iter().zip(&now).map(|(m, v)| m / total - v));
    }
    Ok(out)
}

#[cfg(test)]
mod tests {
    use super::*;
    use motions::{FramePose, POSE_DIM};

    fn walk(speed: f64, frames: usize) -> Motion {
        let frames = (0..frames)
            .map(|k| FramePose {
                pose: [0.0; POSE_DIM],
                transl: [speed * k as f64 / 30.0, 0.9, 0.0],
            })
            .collect();
        Motion::new("walk", 30.0, frames).unwrap()
    }

    #[test]
    fn a_body_that_never_moved_has_no_history() {
        let h = pose_history(&walk(0.0, 10), 9).unwrap();
        assert_eq!(h.len(), HISTORY_SECONDS.len() * HISTORY_VALUES);
        assert!(h.iter().all(|v| v.abs() < 1e-12), "{h:?}");
    }

    /// Walking at a steady speed for longer than the horizon, the weighted mean of the past
    /// positions lags by the speed times the mean age: v / fps * sum k q^k / sum q^k over the
    /// summed frames, q = e^(-1 / (tau fps)); forward is +z when the root has no rotation, so
    /// a walk along +x is sideways in the heading frame and stays along x.
    #[test]
    fn a_steady_walk_lags_by_its_speed_times_the_mean_age() {
        let speed = 1.2;
        let motion = walk(speed, 400);
        let h = pose_history(&motion, 399).unwrap();
        let frames = (HORIZON * 1.0 * 30.0_f64).ceil() as usize;
        for (i, tau) in HISTORY_SECONDS.iter().enumerate() {
            let q = (-1.0 / (tau * 30.0)).exp();
            let (mut num, mut den) = (0.0, 0.0);
            for k in 0..=frames {
                num += k as f64 * q.powi(k as i32);
                den += q.powi(k as i32);
            }
            let expected = -speed / 30.0 * num / den;
            let x = h[i * HISTORY_VALUES + CONDITION_JOINTS * 6];
            assert!(
                (x - expected).abs() < 1e-9,
                "tau {tau}: {x} against {expected}"
            );
            // Rotations never changed, and nothing moved up or forward.
            let block = &h[i * HISTORY_VALUES..(i + 1) * HISTORY_VALUES];
            assert!(
                block[..CONDITION_JOINTS * 6]
                    .iter()
                    .all(|v| v.abs() < 1e-12)
            );
            assert!(
                block[CONDITION_JOINTS * 6 + 1..]
                    .iter()
                    .all(|v| v.abs() < 1e-12)
            );
        }
        // The longer the time constant, the further back the mean.
        let lag = |i: usize| h[i * HISTORY_VALUES + CONDITION_JOINTS * 6];
        assert!(
            lag(0) > lag(1) && lag(1) > lag(2),
            "{} {} {}",
            lag(0),
            lag(1),
            lag(2)
        );
    }

    /// Before its first frame the body stood in that frame's pose: a motion that starts with
    /// 200 more copies of its first frame has the same history at the same moment.
    #[test]
    fn a_motion_started_later_from_the_same_pose_has_the_same_history() {
        let moving = |k: usize| {
            let mut pose = [0.0; POSE_DIM];
            pose[3 * 4] = 0.03 * k as f64;
            pose[1] = 0.02 * k as f64;
            FramePose {
                pose,
                transl: [0.01 * k as f64, 0.9, 0.04 * k as f64],
            }
        };
        let short: Vec<FramePose> = (0..20).map(moving).collect();
        let mut long = vec![short[0]; 200];
        long.extend(&short);
        let short = Motion::new("short", 30.0, short).unwrap();
        let long = Motion::new("long", 30.0, long).unwrap();
        for t in [0, 1, 10, 19] {
            let a = pose_history(&short, t).unwrap();
            let b = pose_history(&long, t + 200).unwrap();
            for (x, y) in a.iter().zip(&b) {
                assert!((x - y).abs() < 1e-9, "frame {t}: {x} against {y}");
            }
        }
        assert!(
            pose_history(&short, 19)
                .unwrap()
                .iter()
                .any(|v| v.abs() > 1e-3)
        );
    }

    /// The history is seen from the current heading: the same walk turned about the vertical
    /// gives the same values.
    #[test]
    fn turning_the_whole_motion_leaves_the_history_as_it_was() {
        let motion = |turn: f64| {
            let frames = (0..60)
                .map(|k| {
                    let mut pose = [0.0; POSE_DIM];
                    pose[1] = turn + 0.01 * k as f64;
                    pose[3 * 4] = 0.02 * k as f64;
                    let (s, c) = turn.sin_cos();
                    let x = 0.04 * k as f64;
                    FramePose {
                        pose,
                        transl: [c * x, 0.9, -s * x],
                    }
                })
                .collect();
            Motion::new("turned", 30.0, frames).unwrap()
        };
        let a = pose_history(&motion(0.0), 59).unwrap();
        let b = pose_history(&motion(1.1), 59).unwrap();
        for (x, y) in a.iter().zip(&b) {
            assert!((x - y).abs() < 1e-9, "{x} against {y}");
        }
        assert!(a.iter().any(|v| v.abs() > 1e-3));
    }
}
