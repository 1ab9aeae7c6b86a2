//! The scripted motions of the library: each sets a few joint groups along one pattern at
//! a moment of its cycle ([`joint_angles`]).

use std::f64::consts::PI;

use super::{Axis, PoseBuilder, Side};

/// A smooth bump in [0, 1] peaking at phase 0 (period 2 pi), zero slope everywhere it meets 0.
fn bump(phase: f64) -> f64 {
    ((1.0 + phase.cos()) / 2.0).powi(3)
}

/// A smooth 0 -> 1 -> 0 cycle over one period.
fn rise(phase: f64) -> f64 {
    (1.0 - phase.cos()) / 2.0
}

/// The time of a scripted motion: `t` seconds at `speed` times its pace, amplitude `a`.
#[derive(Clone, Copy)]
struct Moment {
    t: f64,
    speed: f64,
    a: f64,
}

impl Moment {
    /// The phase (radians) of a cycle of `hz` at this moment.
    fn phase(self, hz: f64) -> f64 {
        2.0 * PI * hz * self.speed * self.t
    }
}

/// Sets the joint angles of motion `name` at time `t` (seconds) and returns an extra vertical
/// lift of the root (metres) for motions that leave the ground.
pub(super) fn joint_angles(name: &str, t: f64, speed: f64, a: f64, b: &mut PoseBuilder) -> f64 {
    let motion: fn(Moment, &mut PoseBuilder) -> f64 = match name {
        "walk" => walk,
        "run" => run,
        "jumping_jacks" => jumping_jacks,
        "arm_raise" => arm_raise,
        "arm_swing" => arm_swing,
        "squat" => squat,
        "torso_twist" => torso_twist,
        "turn" => turn,
        "kick" => kick,
        "sway" => sway,
        other => unreachable!("motion names are checked by MotionSpec::parse: {other}"),
    };
    motion(Moment { t, speed, a }, b)
}

/// Walking in place: legs and arms in counter-phase, a small spine twist.
fn walk(m: Moment, b: &mut PoseBuilder) -> f64 {
    let a = m.a;
    let p = m.phase(0.9);
    b.leg(
        Side::Left,
        a * (5.0 + 22.0 * p.sin()),
        a * (5.0 + 55.0 * bump(p + 1.0)),
        a * 10.0 * bump(p + 1.0),
    );
    b.leg(
        Side::Right,
        a * (5.0 - 22.0 * p.sin()),
        a * (5.0 + 55.0 * bump(p + 1.0 + PI)),
        a * 10.0 * bump(p + 1.0 + PI),
    );
    b.arm(
        Side::Left,
        70.0,
        -a * 15.0 * p.sin(),
        15.0 + a * 10.0 * rise(p + PI),
    );
    b.arm(
        Side::Right,
        70.0,
        a * 15.0 * p.sin(),
        15.0 + a * 10.0 * rise(p),
    );
    b.turn(0, Axis::Y, a * 4.0 * p.sin())
        .turn(3, Axis::Y, -a * 3.0 * p.sin())
        .turn(6, Axis::Y, -a * 2.0 * p.sin());
    0.0
}

/// Running in place: longer strides, bent arms, the trunk leaning forward.
fn run(m: Moment, b: &mut PoseBuilder) -> f64 {
    let a = m.a;
    let p = m.phase(1.25);
    b.leg(
        Side::Left,
        a * (15.0 + 28.0 * p.sin()),
        a * (15.0 + 75.0 * bump(p + 1.0)),
        a * 10.0 * bump(p + 1.0),
    );
    b.leg(
        Side::Right,
        a * (15.0 - 28.0 * p.sin()),
        a * (15.0 + 75.0 * bump(p + 1.0 + PI)),
        a * 10.0 * bump(p + 1.0 + PI),
    );
    b.arm(Side::Left, 70.0, -a * 30.0 * p.sin(), 80.0);
    b.arm(Side::Right, 70.0, a * 30.0 * p.sin(), 80.0);
    b.turn(3, Axis::X, a * 8.0)
        .turn(3, Axis::Y, -a * 5.0 * p.sin())
        .turn(12, Axis::X, -a * 6.0);
    0.0
}

/// Jumping jacks: arms over the head and legs apart together, with a hop.
fn jumping_jacks(m: Moment, b: &mut PoseBuilder) -> f64 {
    let a = m.a;
    let p = m.phase(0.9);
    let open = rise(p);
    b.arm(Side::Left, 70.0 - a * 145.0 * open, 0.0, 10.0);
    b.arm(Side::Right, 70.0 - a * 145.0 * open, 0.0, 10.0);
    b.turn(1, Axis::Z, a * 15.0 * open)
        .turn(2, Axis::Z, -a * 15.0 * open);
    b.turn(7, Axis::Z, -a * 15.0 * open)
        .turn(8, Axis::Z, a * 15.0 * open);
    b.leg(Side::Left, 0.0, a * 10.0 * p.sin().powi(2), 0.0);
    b.leg(Side::Right, 0.0, a * 10.0 * p.sin().powi(2), 0.0);
    a * 0.06 * p.sin().powi(2)
}

/// Both arms raised sideways over the head and lowered.
fn arm_raise(m: Moment, b: &mut PoseBuilder) -> f64 {
    let a = m.a;
    let up = rise(m.phase(0.35));
    b.arm(Side::Left, 70.0 - a * 150.0 * up, 0.0, 10.0);
    b.arm(Side::Right, 70.0 - a * 150.0 * up, 0.0, 10.0);
    0.0
}

/// Arms swinging forward and back in counter-phase, with a knee bounce.
fn arm_swing(m: Moment, b: &mut PoseBuilder) -> f64 {
    let a = m.a;
    let p = m.phase(0.8);
    b.arm(Side::Left, 70.0, a * 55.0 * p.sin(), 20.0);
    b.arm(Side::Right, 70.0, -a * 55.0 * p.sin(), 20.0);
    let bounce = a * 6.0 * rise(2.0 * p);
    b.leg(Side::Left, bounce / 2.0, bounce, bounce / 2.0);
    b.leg(Side::Right, bounce / 2.0, bounce, bounce / 2.0);
    0.0
}

/// Squatting with the feet flat and the arms forward.
fn squat(m: Moment, b: &mut PoseBuilder) -> f64 {
    let a = m.a;
    // Depth is capped: beyond 1.1 the hips would flex past human range (found by the
    // joint-limit test at amplitude 1.5).
    let d = a.min(1.1) * rise(m.phase(0.3));
    // Foot flat: ankle dorsiflexion = knee flexion - hip flexion.
    b.leg(Side::Left, 95.0 * d, 115.0 * d, 20.0 * d);
    b.leg(Side::Right, 95.0 * d, 115.0 * d, 20.0 * d);
    b.turn(3, Axis::X, 25.0 * d)
        .turn(6, Axis::X, 10.0 * d)
        .turn(12, Axis::X, -20.0 * d);
    b.arm(Side::Left, 70.0, 75.0 * d, 10.0);
    b.arm(Side::Right, 70.0, 75.0 * d, 10.0);
    0.0
}

/// The spine twisting about the vertical, the arms held out.
fn torso_twist(m: Moment, b: &mut PoseBuilder) -> f64 {
    let a = m.a;
    let s = a * m.phase(0.4).sin();
    b.turn(3, Axis::Y, 12.0 * s)
        .turn(6, Axis::Y, 12.0 * s)
        .turn(9, Axis::Y, 10.0 * s)
        .turn(12, Axis::Y, -6.0 * s);
    b.arm(Side::Left, 55.0, 20.0, 70.0);
    b.arm(Side::Right, 55.0, 20.0, 70.0);
    0.0
}

/// Turning on the spot at 90 degrees a second, stepping.
fn turn(m: Moment, b: &mut PoseBuilder) -> f64 {
    let a = m.a;
    let p = m.phase(1.2);
    b.turn(0, Axis::Y, 90.0 * m.speed * m.t);
    b.leg(
        Side::Left,
        a * 25.0 * bump(p),
        a * 45.0 * bump(p),
        a * 10.0 * bump(p),
    );
    b.leg(
        Side::Right,
        a * 25.0 * bump(p + PI),
        a * 45.0 * bump(p + PI),
        a * 10.0 * bump(p + PI),
    );
    b.arm(Side::Left, 70.0, 0.0, 20.0);
    b.arm(Side::Right, 70.0, 0.0, 20.0);
    0.0
}

/// A forward kick of the right leg.
fn kick(m: Moment, b: &mut PoseBuilder) -> f64 {
    let a = m.a;
    let k = rise(m.phase(0.5)).powi(2);
    b.leg(
        Side::Right,
        a * 75.0 * k,
        a * 70.0 * 4.0 * k * (1.0 - k),
        -a * 20.0 * k,
    );
    b.leg(Side::Left, a * 5.0 * k, a * 10.0 * k, a * 5.0 * k);
    b.turn(3, Axis::X, -a * 10.0 * k);
    b.arm(Side::Left, 60.0, 30.0, 100.0);
    b.arm(Side::Right, 60.0, 30.0 - a * 20.0 * k, 100.0);
    0.0
}

/// Swaying side to side with a knee bounce.
fn sway(m: Moment, b: &mut PoseBuilder) -> f64 {
    let a = m.a;
    let p = m.phase(0.5);
    let side = a * p.sin();
    b.turn(1, Axis::Z, 6.0 * side)
        .turn(2, Axis::Z, 6.0 * side)
        .turn(7, Axis::Z, -6.0 * side)
        .turn(8, Axis::Z, -6.0 * side);
    let bounce = a * 10.0 * rise(2.0 * p);
    b.leg(Side::Left, bounce / 2.0, bounce, bounce / 2.0);
    b.leg(Side::Right, bounce / 2.0, bounce, bounce / 2.0);
    b.turn(3, Axis::Z, -5.0 * side)
        .turn(6, Axis::Z, -4.0 * side)
        .turn(15, Axis::Z, 4.0 * side);
    b.arm(Side::Left, 65.0 - 10.0 * side, 15.0 * side, 30.0);
    b.arm(Side::Right, 65.0 + 10.0 * side, -15.0 * side, 30.0);
    0.0
}
