//! A body motion: SMPL poses and root translations at a frame rate, with time-correct
//! resampling, blend-in from the canonical pose, and pose windows for learning.

use nalgebra::{UnitQuaternion, Vector3};

use crate::error::{Error, MotionProblem, Result};
use crate::forward::FramePose;
use crate::rotation::{axis_angle_to_quat, quat_to_axis_angle, slerp_axis_angle};
use crate::skeleton::{NUM_JOINTS, POSE_DIM};

/// The frame rate of every motion the engine consumes.
pub const OUTPUT_FPS: f64 = 30.0;

/// Shoulder rotation of the canonical A-pose: the arms 40 degrees below horizontal, as the
/// GarmentCode A-pose bodies.
pub const A_POSE_SHOULDER_DEG: f64 = 40.0;

/// The canonical pose for garments: the T-pose with both shoulders (joints 16, 17) rotated
/// 40 degrees down about the z axis; garment templates are aligned to the body in this pose.
pub fn canonical_a_pose() -> [f64; POSE_DIM] {
    let a = A_POSE_SHOULDER_DEG.to_radians();
    let mut pose = [0.0; POSE_DIM];
    pose[16 * 3 + 2] = -a;
    pose[17 * 3 + 2] = a;
    pose
}

/// A motion: per-frame SMPL poses (72 axis-angle values, radians) and root translations
/// (metres) at `fps` frames per second.
#[derive(Debug, Clone, PartialEq)]
pub struct Motion {
    /// Name (built-in name with parameters, or the file it came from).
    pub name: String,
    /// Frames per second.
    pub fps: f64,
    /// Pose and translation of each frame.
    pub frames: Vec<FramePose>,
    /// Shape coefficients stored with the motion (AMASS files carry them), if any.
    pub betas: Option<Vec<f64>>,
    /// Gender string stored with the motion (AMASS), if any.
    pub gender: Option<String>,
}

/// Blend-in settings: frames interpolating from the canonical A-pose to the motion's first
/// frame, then frames holding the first frame so the cloth settles before the motion starts.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct BlendIn {
    /// Frames of interpolation from the canonical pose (default 30, one second at 30 fps).
    pub blend_frames: usize,
    /// Frames holding the first pose (default 30).
    pub settle_frames: usize,
}

impl Default for BlendIn {
    fn default() -> Self {
        Self {
            blend_frames: 30,
            settle_frames: 30,
        }
    }
}

/// The poses around frame `t` that the surrogate is conditioned on: the `l` previous frames
/// and frame `t`, canonicalized by frame `t`'s heading (see [`Motion::pose_window`]).
#[derive(Debug, Clone, PartialEq)]
pub struct PoseWindow {
    /// The target frame.
    pub frame: usize,
    /// `l + 1` poses, oldest first, the last one frame `t`; root orientations with frame `t`'s
    /// heading removed.
    pub poses: Vec<[f64; POSE_DIM]>,
    /// `l + 1` root translations relative to frame `t`'s, in frame `t`'s heading frame.
    pub transl: Vec<[f64; 3]>,
    /// Frame `t`'s heading (rotation about +y, radians) that was removed.
    pub heading: f64,
}

/// The most frames a motion may have (an hour at 30 fps): more is a damaged file or a typo
/// that would otherwise size allocations.
pub const MAX_MOTION_FRAMES: usize = 108_000;

/// Upper bound on blend-in and settle frames (an hour at 30 fps), for the same reason.
pub const MAX_PREFIX_FRAMES: usize = 108_000;

impl Motion {
    /// Builds a motion, checking that it is non-empty, finite and has a positive rate.
    pub fn new(name: impl Into<String>, fps: f64, frames: Vec<FramePose>) -> Result<Self> {
        let name = name.into();
        if !(fps.is_finite() && fps > 0.0) {
            return Err(Error::BadMotion {
                name,
                problem: MotionProblem::FrameRate(fps),
            });
        }
        if frames.is_empty() {
            return Err(Error::BadMotion {
                name,
                problem: MotionProblem::NoFrames,
            });
        }
        if let Some(k) = frames
            .iter()
            .position(|f| f.pose.iter().chain(&f.transl).any(|v| !v.is_finite()))
        {
            return Err(Error::BadMotion {
                name,
                problem: MotionProblem::NonFiniteFrame(k),
            });
        }
        Ok(Self {
            name,
            fps,
            frames,
            betas: None,
            gender: None,
        })
    }

    /// Number of frames.
    pub fn len(&self) -> usize {
        self.frames.len()
    }

    /// Whether the motion has no frames (never true for a motion built with [`Motion::new`]).
    pub fn is_empty(&self) -> bool {
        self.frames.is_empty()
    }

    /// Duration in seconds from the first to the last frame.
    pub fn duration(&self) -> f64 {
        (self.frames.len() - 1) as f64 / self.fps
    }

    /// Largest rotation of each joint away from the T-pose over all frames, degrees (the
    /// axis-angle magnitude; joint 0 is the root orientation).
    pub fn max_joint_angles_deg(&self) -> [f64; NUM_JOINTS] {
        std::array::from_fn(|j| {
            self.frames
                .iter()
                .map(|f| {
                    Vector3::new(f.pose[3 * j], f.pose[3 * j + 1], f.pose[3 * j + 2])
                        .norm()
                        .to_degrees()
                })
                .fold(0.0, f64::max)
        })
    }

    /// Resamples by time to `fps`: output frame k is at t = k / fps, for every t within the
    /// motion; joint rotations are slerped (shorter arc, so q/-q flips in mocap do no harm) and
    /// translations lerped between the two source frames around t. Works for any source rate
    /// (60, 100, 120, 250 fps ...), multiple of the target or not.
    pub fn resample(&self, fps: f64) -> Result<Motion> {
        let frames = self.duration() * fps;
        if frames > MAX_MOTION_FRAMES as f64 {
            return Err(Error::BadMotion {
                name: self.name.clone(),
                problem: MotionProblem::TooLong {
                    fps,
                    frames,
                    max: MAX_MOTION_FRAMES,
                },
            });
        }
        if !(fps.is_finite() && fps > 0.0) {
            return Err(Error::BadMotion {
                name: self.name.clone(),
                problem: MotionProblem::FrameRate(fps),
            });
        }
        if (fps - self.fps).abs() < 1e-9 {
            return Ok(self.clone());
        }
        let duration = self.duration();
        let count = (duration * fps + 1e-9).floor() as usize + 1;
        let frames = (0..count)
            .map(|k| {
                let s = (k as f64 / fps) * self.fps;
                let i = (s.floor() as usize).min(self.frames.len() - 1);
                let j = (i + 1).min(self.frames.len() - 1);
                let u = s - i as f64;
                interpolate(&self.frames[i], &self.frames[j], u)
            })
            .collect();
        let mut out = Motion::new(self.name.clone(), fps, frames)?;
        out.betas = self.betas.clone();
        out.gender = self.gender.clone();
        Ok(out)
    }

    /// Prefixes the motion with `blend_frames` frames easing (smoothstep in time, slerp per
    /// joint) from `canonical` to the first frame, then `settle_frames` frames holding the first
    /// frame. The root translation is held at the first frame's throughout the prefix.
    pub fn with_blend_in(&self, canonical: &[f64; POSE_DIM], blend: BlendIn) -> Motion {
        let first = self.frames[0];
        let start = FramePose {
            pose: *canonical,
            transl: first.transl,
        };
        let mut frames = Vec::with_capacity(blend.blend_frames + blend.settle_frames + self.len());
        for k in 0..blend.blend_frames {
            let u = k as f64 / blend.blend_frames as f64;
            frames.push(interpolate(&start, &first, u * u * (3.0 - 2.0 * u)));
        }
        frames.extend(std::iter::repeat_n(first, blend.settle_frames));
        frames.extend_from_slice(&self.frames);
        Motion {
            name: self.name.clone(),
            fps: self.fps,
            frames,
            betas: self.betas.clone(),
            gender: self.gender.clone(),
        }
    }

    /// The pose window for frame `t`: frames `t - l ..= t` (indices before 0 repeat frame 0).
    ///
    /// Canonicalization: the heading of frame `t` (the root's rotation about the vertical +y
    /// axis, taken from where the root turns its forward axis +z) is removed from every root
    /// orientation in the window, and translations are expressed relative to frame `t`'s in
    /// that heading frame. Gravity stays along -y, so tilt is kept; only where the body walks
    /// to and which way it faces are factored out.
    pub fn pose_window(&self, t: usize, l: usize) -> Result<PoseWindow> {
        if t >= self.len() {
            return Err(Error::FrameOutOfRange {
                frame: t,
                len: self.len(),
            });
        }
        let current = &self.frames[t];
        let heading = heading_of(&current.pose);
        let unturn = UnitQuaternion::from_axis_angle(&Vector3::y_axis(), -heading);
        let origin = Vector3::from(current.transl);
        let mut poses = Vec::with_capacity(l + 1);
        let mut transl = Vec::with_capacity(l + 1);
        for k in 0..=l {
            let f = &self.frames[(t + k).saturating_sub(l)];
            let mut pose = f.pose;
            let root = unturn * axis_angle_to_quat([pose[0], pose[1], pose[2]]);
            pose[..3].copy_from_slice(&quat_to_axis_angle(&root));
            poses.push(pose);
            transl.push((unturn * (Vector3::from(f.transl) - origin)).into());
        }
        Ok(PoseWindow {
            frame: t,
            poses,
            transl,
            heading,
        })
    }
}

/// Heading of a pose: the angle about +y of the root's forward axis (+z) projected on the
/// ground plane.
pub fn heading_of(pose: &[f64; POSE_DIM]) -> f64 {
    let forward = axis_angle_to_quat([pose[0], pose[1], pose[2]]) * Vector3::z();
    forward.x.atan2(forward.z)
}

fn interpolate(a: &FramePose, b: &FramePose, u: f64) -> FramePose {
    if u <= 0.0 {
        return *a;
    }
    if u >= 1.0 {
        return *b;
    }
    let mut pose = [0.0; POSE_DIM];
    for j in 0..NUM_JOINTS {
        let r = slerp_axis_angle(
            [a.pose[3 * j], a.pose[3 * j + 1], a.pose[3 * j + 2]],
            [b.pose[3 * j], b.pose[3 * j + 1], b.pose[3 * j + 2]],
            u,
        );
        pose[3 * j..3 * j + 3].copy_from_slice(&r);
    }
    let transl = std::array::from_fn(|c| a.transl[c] + (b.transl[c] - a.transl[c]) * u);
    FramePose { pose, transl }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn constant_turn(fps: f64, seconds: f64, rad_per_s: f64) -> Motion {
        let n = (seconds * fps).round() as usize + 1;
        let frames = (0..n)
            .map(|k| {
                let t = k as f64 / fps;
                let mut pose = [0.0; POSE_DIM];
                pose[1] = rad_per_s * t; // root about y
                pose[18 * 3] = 0.5 * (2.0 * t).sin(); // an elbow
                FramePose {
                    pose,
                    transl: [t, 0.0, 0.0],
                }
            })
            .collect();
        Motion::new("test", fps, frames).unwrap()
    }

    #[test]
    fn resampling_is_by_time_for_any_source_rate() {
        for fps in [60.0, 100.0, 120.0, 250.0, 29.97] {
            let m = constant_turn(fps, 2.0, 0.8).resample(OUTPUT_FPS).unwrap();
            assert_eq!(m.len(), 61, "source {fps} fps");
            for (k, f) in m.frames.iter().enumerate() {
                let t = k as f64 / OUTPUT_FPS;
                assert!(
                    (f.pose[1] - 0.8 * t).abs() < 1e-9,
                    "{fps} fps, frame {k}: root {} vs {}",
                    f.pose[1],
                    0.8 * t
                );
                assert!((f.transl[0] - t).abs() < 1e-9);
                // The elbow angle is a sine: linear-in-angle interpolation errs by O(h^2).
                assert!((f.pose[54] - 0.5 * (2.0 * t).sin()).abs() < 1e-3);
            }
        }
    }

    #[test]
    fn blend_in_starts_at_the_canonical_pose_and_reaches_the_first_frame() {
        let m = constant_turn(30.0, 1.0, 0.5);
        let b = m.with_blend_in(
            &canonical_a_pose(),
            BlendIn {
                blend_frames: 10,
                settle_frames: 5,
            },
        );
        assert_eq!(b.len(), m.len() + 15);
        assert_eq!(b.frames[0].pose, canonical_a_pose());
        assert_eq!(b.frames[10], m.frames[0]);
        assert_eq!(b.frames[14], m.frames[0]);
        assert_eq!(b.frames[15..], m.frames[..]);
    }

    #[test]
    fn pose_window_removes_heading_and_translation() {
        let m = constant_turn(30.0, 2.0, 0.9);
        let w = m.pose_window(40, 3).unwrap();
        assert_eq!(w.poses.len(), 4);
        let last = w.poses.last().unwrap();
        assert!(
            last[..3].iter().all(|v| v.abs() < 1e-12),
            "current root not canonical: {:?}",
            &last[..3]
        );
        assert!(w.transl.last().unwrap().iter().all(|v| v.abs() < 1e-12));
        // The previous frame turned 0.9/30 rad less.
        assert!(
            (w.poses[2][1] + 0.9 / 30.0).abs() < 1e-9,
            "previous root {:?}",
            &w.poses[2][..3]
        );
        let early = m.pose_window(1, 3).unwrap();
        assert_eq!(
            early.poses[0], early.poses[1],
            "frames before 0 repeat frame 0"
        );
    }

    #[test]
    fn empty_bad_rate_or_non_finite_is_rejected_by_variant() {
        let problem = |r: Result<Motion>| match r {
            Err(Error::BadMotion { name, problem }) if name == "x" => problem,
            other => panic!("expected a BadMotion error, got {other:?}"),
        };
        assert_eq!(
            problem(Motion::new("x", 30.0, vec![])),
            MotionProblem::NoFrames
        );
        let f = FramePose {
            pose: [0.0; POSE_DIM],
            transl: [0.0; 3],
        };
        assert_eq!(
            problem(Motion::new("x", 0.0, vec![f])),
            MotionProblem::FrameRate(0.0)
        );
        assert!(matches!(
            problem(Motion::new("x", f64::NAN, vec![f])),
            MotionProblem::FrameRate(r) if r.is_nan()
        ));
        let mut bad = f;
        bad.transl[1] = f64::INFINITY;
        assert_eq!(
            problem(Motion::new("x", 30.0, vec![f, bad])),
            MotionProblem::NonFiniteFrame(1)
        );
        let m = Motion::new("x", 30.0, vec![f, f]).unwrap();
        assert!(matches!(
            problem(m.resample(-1.0)),
            MotionProblem::FrameRate(_)
        ));
        assert!(matches!(
            problem(m.resample(1e9)),
            MotionProblem::TooLong { .. }
        ));
        assert!(matches!(
            m.pose_window(2, 3),
            Err(Error::FrameOutOfRange { frame: 2, len: 2 })
        ));
    }
}
