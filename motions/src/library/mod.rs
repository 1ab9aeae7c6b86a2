//! The built-in motion library: procedural, parameterized motions at 30 fps.
//!
//! A motion is named `NAME` or `NAME:key=value,...` with the keys `speed` (tempo multiplier,
//! default 1, range 0.25-3), `amplitude` (joint-angle multiplier, default 1, range 0-1.5),
//! `duration` (seconds, default per motion, at most 600) and, for `random` and `random_legs`
//! only, `seed` (a whole number: which random motion). Variants of the same motion differ in these
//! parameters, so training and held-out test sets can use different ones.
//!
//! Joint angles are smooth functions of time (sines and smooth bumps) within human ranges,
//! eased in over the first 0.6 s so every motion starts from standing. The
//! root translation is not scripted: it comes from planting the feet ([`plant_feet`]), so gait
//! motions walk forward without foot sliding and squats lower the pelvis.

use std::f64::consts::PI;

use nalgebra::{UnitQuaternion, Vector3};

use crate::body_model::BodyModel;
use crate::error::{Error, Result};
use crate::forward::{FramePose, ShapedBody};
use crate::motion::{Motion, OUTPUT_FPS};
use crate::rotation::quat_to_axis_angle;
use crate::skeleton::{NUM_JOINTS, POSE_DIM};

mod scripted;
use scripted::joint_angles;

/// One entry of the library.
#[derive(Debug, Clone, Copy)]
pub struct MotionInfo {
    /// Name used on the command line.
    pub name: &'static str,
    /// What the body does.
    pub description: &'static str,
    /// Default duration, seconds.
    pub default_duration: f64,
}

/// The built-in motions.
pub const MOTIONS: [MotionInfo; 12] = [
    MotionInfo {
        name: "walk",
        description: "walking forward at about 1 m/s, arms swinging",
        default_duration: 4.0,
    },
    MotionInfo {
        name: "run",
        description: "jogging forward, trunk leaning, elbows bent",
        default_duration: 3.0,
    },
    MotionInfo {
        name: "jumping_jacks",
        description: "jumping jacks: arms overhead and legs apart, with hops",
        default_duration: 4.0,
    },
    MotionInfo {
        name: "arm_raise",
        description: "both arms raised sideways overhead and lowered",
        default_duration: 6.0,
    },
    MotionInfo {
        name: "arm_swing",
        description: "arms swinging forward and back in opposition",
        default_duration: 4.0,
    },
    MotionInfo {
        name: "squat",
        description: "deep squats with arms reaching forward",
        default_duration: 6.0,
    },
    MotionInfo {
        name: "torso_twist",
        description: "upper body twisting left and right, elbows bent",
        default_duration: 5.0,
    },
    MotionInfo {
        name: "turn",
        description: "stepping in place while turning left (90 deg/s)",
        default_duration: 4.0,
    },
    MotionInfo {
        name: "kick",
        description: "front kicks with the right leg, arms on guard",
        default_duration: 4.0,
    },
    MotionInfo {
        name: "sway",
        description: "dance-like side-to-side sway with knee bounce and arm sway",
        default_duration: 6.0,
    },
    MotionInfo {
        name: "random",
        description: "every joint group on its own smooth random course (`seed` picks which)",
        default_duration: 6.0,
    },
    MotionInfo {
        name: "random_legs",
        description: "`random` with the legs' full range: hips flexed to 60 deg and spread, knees to 70",
        default_duration: 6.0,
    },
];

/// A parsed motion request: a library name and its parameters.
#[derive(Debug, Clone, PartialEq)]
pub struct MotionSpec {
    /// Library name.
    pub name: String,
    /// Tempo multiplier.
    pub speed: f64,
    /// Joint-angle multiplier.
    pub amplitude: f64,
    /// Duration, seconds.
    pub duration: f64,
    /// Which random motion (`random` and `random_legs` only; 0 for the others).
    pub seed: u64,
}

impl MotionSpec {
    /// Parses `NAME` or `NAME:speed=1.2,amplitude=0.8,duration=5`.
    pub fn parse(text: &str) -> Result<Self> {
        let (name, params) = text.split_once(':').unwrap_or((text, ""));
        let unknown = |reason: String| Error::UnknownMotion {
            name: text.to_string(),
            reason,
        };
        let info = find(name).ok_or_else(|| {
            let names: Vec<&str> = MOTIONS.iter().map(|m| m.name).collect();
            unknown(format!("built-in motions are {}", names.join(", ")))
        })?;
        let mut spec = Self {
            name: info.name.to_string(),
            speed: 1.0,
            amplitude: 1.0,
            duration: info.default_duration,
            seed: 0,
        };
        for kv in params.split(',').filter(|s| !s.trim().is_empty()) {
            let (k, v) = kv
                .split_once('=')
                .ok_or_else(|| unknown(format!("'{kv}' is not key=value")))?;
            if k.trim() == "seed" {
                if LegRange::of(&spec.name).is_none() {
                    return Err(unknown(
                        "only `random` and `random_legs` take a seed".into(),
                    ));
                }
                spec.seed = v.trim().parse().map_err(|_| {
                    unknown(format!(
                        "seed '{v}' is not a whole number from 0 to {}",
                        u64::MAX
                    ))
                })?;
                continue;
            }
            let value: f64 = v
                .trim()
                .parse()
                .map_err(|_| unknown(format!("'{v}' is not a number")))?;
            let (slot, lo, hi) = match k.trim() {
                "speed" => (&mut spec.speed, 0.25, 3.0),
                "amplitude" => (&mut spec.amplitude, 0.0, 1.5),
                "duration" => (&mut spec.duration, 1.0 / OUTPUT_FPS, 600.0),
                other => {
                    return Err(unknown(format!(
                        "unknown parameter '{other}' (speed, amplitude, duration, seed)"
                    )));
                }
            };
            if !(value.is_finite() && value >= lo && value <= hi) {
                return Err(unknown(format!("{k} = {value} is outside [{lo}, {hi}]")));
            }
            *slot = value;
        }
        Ok(spec)
    }

    /// The canonical text form (parameters that differ from the defaults only).
    pub fn label(&self) -> String {
        let info = find(&self.name).expect("spec names come from the library");
        let mut parts = Vec::new();
        if self.speed != 1.0 {
            parts.push(format!("speed={}", self.speed));
        }
        if self.amplitude != 1.0 {
            parts.push(format!("amplitude={}", self.amplitude));
        }
        if self.duration != info.default_duration {
            parts.push(format!("duration={}", self.duration));
        }
        if self.seed != 0 {
            parts.push(format!("seed={}", self.seed));
        }
        if parts.is_empty() {
            self.name.clone()
        } else {
            format!("{}:{}", self.name, parts.join(","))
        }
    }

    /// Generates the motion at 30 fps for a body, planting the feet of that skeleton.
    pub fn generate(&self, model: &BodyModel, shaped: &ShapedBody) -> Result<Motion> {
        let count = (self.duration * OUTPUT_FPS).round().max(1.0) as usize;
        let random = LegRange::of(&self.name).map(|legs| (RandomMotion::new(self.seed), legs));
        let frames: Vec<FramePose> = (0..count)
            .map(|k| {
                let t = k as f64 / OUTPUT_FPS;
                let mut b = PoseBuilder::default();
                let a = self.amplitude * ease_in(t);
                let lift = match &random {
                    Some((random, legs)) => random.joint_angles(t, self.speed, a, *legs, &mut b),
                    None => joint_angles(&self.name, t, self.speed, a, &mut b),
                };
                FramePose {
                    pose: b.pose(),
                    transl: [0.0, lift, 0.0],
                }
            })
            .collect();
        let frames = plant_feet(model, shaped, frames);
        Motion::new(self.label(), OUTPUT_FPS, frames)
    }
}

/// Looks up a library entry by name.
pub fn find(name: &str) -> Option<&'static MotionInfo> {
    MOTIONS.iter().find(|m| m.name == name)
}

/// Accumulates joint rotations: each `turn` is applied after the joint's earlier turns (about
/// axes of the parent's frame, which in the T-pose rest is aligned with the world).
struct PoseBuilder {
    rotations: [UnitQuaternion<f64>; NUM_JOINTS],
}

impl Default for PoseBuilder {
    fn default() -> Self {
        Self {
            rotations: [UnitQuaternion::identity(); NUM_JOINTS],
        }
    }
}

impl PoseBuilder {
    fn turn(&mut self, joint: usize, axis: Axis, degrees: f64) -> &mut Self {
        let axis = match axis {
            Axis::X => Vector3::x_axis(),
            Axis::Y => Vector3::y_axis(),
            Axis::Z => Vector3::z_axis(),
        };
        self.rotations[joint] =
            UnitQuaternion::from_axis_angle(&axis, degrees.to_radians()) * self.rotations[joint];
        self
    }

    /// Flexes a hip (thigh forward), knee (shin back) and ankle (toes up) of one side.
    fn leg(&mut self, side: Side, hip_flex: f64, knee_flex: f64, ankle_dorsi: f64) {
        let (hip, knee, ankle) = match side {
            Side::Left => (1, 4, 7),
            Side::Right => (2, 5, 8),
        };
        self.turn(hip, Axis::X, -hip_flex)
            .turn(knee, Axis::X, knee_flex)
            .turn(ankle, Axis::X, -ankle_dorsi);
    }

    /// Spreads a hip outward by `degrees` (inward if negative), turning the ankle back so the
    /// foot stays flat.
    fn spread_leg(&mut self, side: Side, degrees: f64) {
        let (hip, ankle, s) = match side {
            Side::Left => (1, 7, 1.0),
            Side::Right => (2, 8, -1.0),
        };
        self.turn(hip, Axis::Z, s * degrees)
            .turn(ankle, Axis::Z, -s * degrees);
    }

    /// Places an arm: `down` degrees below horizontal, `forward` degrees of swing to the front,
    /// elbow bent `elbow` degrees towards the front.
    fn arm(&mut self, side: Side, down: f64, forward: f64, elbow: f64) {
        let (shoulder, el, s) = match side {
            Side::Left => (16, 18, 1.0),
            Side::Right => (17, 19, -1.0),
        };
        self.turn(shoulder, Axis::Z, -s * down)
            .turn(shoulder, Axis::X, -forward)
            .turn(el, Axis::Y, -s * elbow);
    }

    fn pose(&self) -> [f64; POSE_DIM] {
        let mut pose = [0.0; POSE_DIM];
        for (j, q) in self.rotations.iter().enumerate() {
            pose[3 * j..3 * j + 3].copy_from_slice(&quat_to_axis_angle(q));
        }
        pose
    }
}

#[derive(Clone, Copy)]
enum Axis {
    X,
    Y,
    Z,
}

#[derive(Clone, Copy)]
enum Side {
    Left,
    Right,
}

/// Seconds over which a motion's amplitude eases in from standing, so the body (and the root
/// moved by foot planting) starts at rest instead of mid-stride.
const EASE_IN_SECONDS: f64 = 0.6;

fn ease_in(t: f64) -> f64 {
    let u = (t / EASE_IN_SECONDS).min(1.0);
    u * u * (3.0 - 2.0 * u)
}

/// How far a random motion moves the legs.
#[derive(Debug, Clone, Copy, PartialEq)]
enum LegRange {
    /// `random`: the hips flex -4 to 20 degrees and the knees 0-24 at amplitude 1, as when
    /// standing and stepping; the hips never spread.
    Standing,
    /// `random_legs`: the hips flex -20 to 60 degrees and spread -5 to 20, the knees 0-70.
    /// Of the other training motions only `squat` flexes a hip past 56 degrees (both at once)
    /// and none spreads them, while a skirt swings from the legs (a kick flexes one hip to 75
    /// degrees with the other straight, a sway rocks the pelvis on the hips).
    Full,
}

impl LegRange {
    /// The leg range of a random motion by its library name; `None` for the scripted ones.
    fn of(name: &str) -> Option<Self> {
        match name {
            "random" => Some(Self::Standing),
            "random_legs" => Some(Self::Full),
            _ => None,
        }
    }
}

/// The `random` motions: each joint group follows its own sum of two sines, with frequencies
/// (0.2-0.8 Hz), phases and weights drawn from the seed, within human ranges. The scripted
/// motions each move a few joint groups along one pattern (walking twists the spine 3
/// degrees); a training set needs poses between and beyond them, as a large motion-capture
/// collection (AMASS) would give it. Arms stay away from the torso (never lower than the
/// standing 70 degrees) so the body does not pass through itself.
struct RandomMotion {
    /// One course per channel, in [-1, 1]: see [`RandomMotion::joint_angles`].
    courses: [[(f64, f64, f64); 2]; RANDOM_CHANNELS],
}

/// Spine bend, twist and side bend; neck turn and nod; per side: arm lift, arm swing, elbow,
/// hip flexion, knee; then per side the hip spread (drawn last, so `random`'s first 15
/// courses are the same as before `random_legs` was added, which does not use it).
const RANDOM_CHANNELS: usize = 17;

impl RandomMotion {
    fn new(seed: u64) -> Self {
        use rand::{Rng, SeedableRng};
        let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(seed);
        let courses = std::array::from_fn(|_| {
            let weight: f64 = rng.random_range(0.3..0.7);
            let mut term = |w: f64| {
                let hz = rng.random_range(0.2..0.8);
                let phase = rng.random_range(0.0..2.0 * PI);
                (hz, phase, w)
            };
            [term(weight), term(1.0 - weight)]
        });
        Self { courses }
    }

    /// Sets the joint angles at time `t`; returns no lift (the feet stay on the ground).
    fn joint_angles(&self, t: f64, speed: f64, a: f64, legs: LegRange, b: &mut PoseBuilder) -> f64 {
        let course = |c: usize| -> f64 {
            self.courses[c]
                .iter()
                .map(|(hz, phase, w)| w * (2.0 * PI * hz * speed * t + phase).sin())
                .sum()
        };
        // Degrees at amplitude 1, per spine joint (3 of them): bend forward 4 +- 6, twist +- 10,
        // side bend +- 4.
        let (bend, twist, side_bend) = (course(0), course(1), course(2));
        for joint in [3, 6, 9] {
            b.turn(joint, Axis::X, a * (4.0 + 6.0 * bend))
                .turn(joint, Axis::Y, a * 10.0 * twist)
                .turn(joint, Axis::Z, a * 4.0 * side_bend);
        }
        b.turn(12, Axis::Y, a * 15.0 * course(3))
            .turn(12, Axis::X, a * 8.0 * course(4));
        for (side, first, spread) in [(Side::Left, 5, 15), (Side::Right, 10, 16)] {
            let lift = 25.0 * (1.0 + course(first));
            b.arm(
                side,
                70.0 - a * lift,
                a * (10.0 + 30.0 * course(first + 1)),
                15.0 + a * 35.0 * (1.0 + course(first + 2)),
            );
            let (hip, knee) = match legs {
                LegRange::Standing => (
                    8.0 + 12.0 * course(first + 3),
                    12.0 * (1.0 + course(first + 4)),
                ),
                LegRange::Full => {
                    // Spread the hip outward (the foot kept flat) before flexing it, as
                    // `jumping_jacks` does.
                    b.spread_leg(side, a * (7.5 + 12.5 * course(spread)));
                    (
                        20.0 + 40.0 * course(first + 3),
                        35.0 * (1.0 + course(first + 4)),
                    )
                }
            };
            b.leg(side, a * hip, a * knee, 0.0);
        }
        0.0
    }
}

/// Softness of the stance-foot choice, metres: feet closer in height than this share the stance.
const STANCE_SOFTNESS: f64 = 0.02;
/// Width (frames) of the Gaussian that smooths the planted horizontal root velocity, so a
/// stance change never jerks the body (a sixth of a second at 30 fps).
const VELOCITY_SMOOTHING_FRAMES: f64 = 5.0;

/// Sets each frame's root translation so the feet stay planted: horizontally, the root moves
/// opposite to the stance foot (the lower one, softly weighted) so that foot does not slide;
/// vertically, the lower foot stays at its first-frame height. Any lift already in a frame's
/// translation (hops) is added on top. The root velocity is smoothed over about a sixth of a
/// second, so stance changes do not jerk the body (at the cost of a few millimetres of slip
/// around touch-down).
pub fn plant_feet(
    model: &BodyModel,
    shaped: &ShapedBody,
    frames: Vec<FramePose>,
) -> Vec<FramePose> {
    let feet = |f: &FramePose| {
        let g = model.joint_transforms(
            shaped,
            &FramePose {
                pose: f.pose,
                transl: [0.0; 3],
            },
        );
        let side = |ankle: usize, ball: usize| {
            let (a, b) = (g[ankle].translation, g[ball].translation);
            let low = if a.y < b.y { a } else { b };
            (low, a.y.min(b.y))
        };
        [side(7, 10), side(8, 11)]
    };
    let soft_min = |l: f64, r: f64| {
        let m = l.min(r);
        m - STANCE_SOFTNESS
            * ((-(l - m) / STANCE_SOFTNESS).exp() + (-(r - m) / STANCE_SOFTNESS).exp()).ln()
    };
    // Per frame: the root's step that keeps the stance foot still (horizontal) and the lower
    // foot at its first-frame height (vertical).
    let mut steps = vec![[0.0; 3]; frames.len()];
    let mut previous: Option<(Vector3<f64>, Vector3<f64>, f64)> = None;
    for (k, f) in frames.iter().enumerate() {
        let [(pl, yl), (pr, yr)] = feet(f);
        let low = soft_min(yl, yr);
        if let Some((ql, qr, previous_low)) = previous {
            let wl = 1.0 / (1.0 + ((yl - yr) / STANCE_SOFTNESS).exp());
            let delta: Vector3<f64> = (pl - ql) * wl + (pr - qr) * (1.0 - wl);
            steps[k] = [-delta.x, previous_low - low, -delta.z];
        }
        previous = Some((pl, pr, low));
    }
    let reach = (3.0 * VELOCITY_SMOOTHING_FRAMES) as isize;
    let mut root = [0.0; 3];
    let mut out = Vec::with_capacity(frames.len());
    for (k, f) in frames.iter().enumerate() {
        if k > 0 {
            let (mut sum, mut norm) = ([0.0; 3], 0.0);
            for d in -reach..=reach {
                let i = k as isize + d;
                if i >= 1 && (i as usize) < frames.len() {
                    let w = (-0.5 * (d as f64 / VELOCITY_SMOOTHING_FRAMES).powi(2)).exp();
                    for c in 0..3 {
                        sum[c] += w * steps[i as usize][c];
                    }
                    norm += w;
                }
            }
            for c in 0..3 {
                root[c] += sum[c] / norm;
            }
        }
        out.push(FramePose {
            pose: f.pose,
            transl: [root[0], root[1] + f.transl[1], root[2]],
        });
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn parameters_parse_and_print_back() {
        let spec = MotionSpec::parse("random:seed=3,speed=1.2").unwrap();
        assert_eq!((spec.seed, spec.speed), (3, 1.2));
        assert_eq!(spec.label(), "random:speed=1.2,seed=3");
        assert_eq!(MotionSpec::parse(&spec.label()).unwrap(), spec);
        assert_eq!(MotionSpec::parse("walk").unwrap().label(), "walk");
        for (bad, why) in [
            ("walk:seed=1", "only `random` and `random_legs`"),
            ("random:seed=1.5", "whole number"),
            ("random:seed=-1", "whole number"),
            ("walk:amplitude=2", "outside"),
            ("walk:pace=1", "unknown parameter"),
            ("fly", "built-in motions are"),
        ] {
            let message = MotionSpec::parse(bad).unwrap_err().to_string();
            assert!(message.contains(why), "{bad}: {message}");
        }
    }

    /// A library motion on the default body at its rest shape.
    fn generate(text: &str) -> Motion {
        let model = BodyModel::default_body();
        let shaped = model.shape(&[]).unwrap();
        MotionSpec::parse(text)
            .unwrap()
            .generate(&model, &shaped)
            .unwrap()
    }

    #[test]
    fn a_random_motion_is_fixed_by_its_seed_and_moves_the_spine() {
        let one = generate("random:seed=1");
        assert_eq!(one.frames, generate("random:seed=1").frames);
        assert_ne!(one.frames, generate("random:seed=2").frames);
        // The spine twists (about y) more than walking's 3 degrees per joint somewhere.
        let twist = |m: &Motion| {
            m.frames
                .iter()
                .map(|f| f.pose[3 * 3 + 1].abs().to_degrees())
                .fold(0.0, f64::max)
        };
        assert!(twist(&one) > 5.0, "{}", twist(&one));
        assert!(twist(&generate("walk")) < 5.0);
    }

    #[test]
    fn random_legs_shares_the_upper_body_and_moves_the_legs_further() {
        let standing = generate("random:seed=5,amplitude=1.3");
        let legs = generate("random_legs:seed=5,amplitude=1.3");
        assert_eq!(
            legs.frames,
            generate("random_legs:seed=5,amplitude=1.3").frames
        );
        // Spine, neck, shoulders and elbows follow the same courses.
        for (a, b) in standing.frames.iter().zip(&legs.frames) {
            for j in [3, 6, 9, 12, 16, 17, 18, 19] {
                assert_eq!(
                    a.pose[3 * j..3 * j + 3],
                    b.pose[3 * j..3 * j + 3],
                    "joint {j}"
                );
            }
        }
        // Largest hip turn over both hips, and largest spread (the axis-angle's z part).
        let hips = |m: &Motion| {
            let mut turn: f64 = 0.0;
            let mut spread: f64 = 0.0;
            for f in &m.frames {
                for hip in [1, 2] {
                    let r = &f.pose[3 * hip..3 * hip + 3];
                    turn = turn.max(r.iter().map(|x| x * x).sum::<f64>().sqrt().to_degrees());
                    spread = spread.max(r[2].abs().to_degrees());
                }
            }
            (turn, spread)
        };
        let (standing_turn, standing_spread) = hips(&standing);
        let (legs_turn, legs_spread) = hips(&legs);
        assert!(
            standing_turn < 35.0 && standing_spread < 1e-9,
            "{standing_turn} {standing_spread}"
        );
        assert!(
            legs_turn > 45.0 && legs_spread > 8.0,
            "{legs_turn} {legs_spread}"
        );
    }
}
