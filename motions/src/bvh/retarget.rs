//! Retargeting a BVH skeleton's motion onto the 24 SMPL joints.
//!
//! A plain copy of local rotations is wrong whenever the two rest poses differ (CMU's rest pose
//! has the legs splayed about 20 degrees; SMPL's hangs them straight). Instead each SMPL joint
//! takes the *world* rotation of the BVH joint that drives it, followed by a fixed per-bone
//! alignment `A_j`: the rotation taking the SMPL rest bone direction onto the BVH rest bone
//! direction. Then every SMPL bone points where the capture's bone points, in every frame:
//!
//! `W_j(t) = C G_k(t) C^T A_j`,  local `R_j = W_parent^T W_j`,
//!
//! with `G_k` the BVH joint's world rotation and `C` the turn from the file's axes to SMPL's
//! (y up, facing +z, +x the body's left), read off the rest pose and snapped to the nearest
//! axes. The trunk (spine to head) is aligned as a whole ([`TRUNK`]), so SMPL's curved spine
//! keeps its rest shape while it turns as the capture's does. BVH joints with no SMPL counterpart (fingers, a second neck joint, CMU's `LHipJoint`)
//! are dropped: their rotations reach the SMPL body through the world rotations of the joints
//! below them. The root translation is the driving joint's position times the file's metres
//! per unit: the map's, or the SMPL legs' length over the capture's, so the feet of the body
//! that wears the motion travel as the capture's feet did.

use nalgebra::{Matrix3, Rotation3, Unit, UnitQuaternion, Vector3};

use crate::bvh::joint_map::JointMap;
use crate::bvh::parse::Bvh;
use crate::error::{Error, Result};
use crate::forward::{FramePose, ShapedBody};
use crate::motion::Motion;
use crate::rotation::quat_to_axis_angle;
use crate::skeleton::{JOINT_NAMES, NUM_JOINTS, POSE_DIM, SMPL_PARENTS};

/// Along the limbs, the SMPL joint whose direction from each joint defines that joint's bone
/// (`None`: the joint's rest alignment is its parent's, or the trunk's).
const BONE_CHILD: [Option<usize>; NUM_JOINTS] = [
    None,
    Some(4),
    Some(5),
    None,
    Some(7),
    Some(8),
    None,
    Some(10),
    Some(11),
    None,
    None,
    None,
    None,
    Some(16),
    Some(17),
    None,
    Some(18),
    Some(19),
    Some(20),
    Some(21),
    Some(22),
    Some(23),
    None,
    None,
];

/// The trunk: spine1, spine2, spine3, neck and head share one rest alignment, from the pelvis
/// to the top of the trunk. SMPL's rest spine curves (spine2 to spine3 leans 25 degrees
/// forward) where captures draw straight segments; aligning each trunk bone to the capture's
/// would bend the SMPL torso at rest, deforming the chest a top is worn on.
const TRUNK: [usize; 5] = [3, 6, 9, 12, 15];

/// A first frame this far (degrees, any mapped joint) from the second is a reference pose,
/// not motion (cgspeed's CMU files start with one): at 60 fps and up no limb turns so far in
/// one frame.
pub const REFERENCE_FRAME_JUMP_DEG: f64 = 45.0;

/// What retargeting did, for `motions show` and the docs of a dataset.
#[derive(Debug, Clone, PartialEq)]
pub struct Report {
    /// The joint map used: a built-in name or the map file.
    pub map: String,
    /// (SMPL joint, BVH joint) pairs, in SMPL order.
    pub mapped: Vec<(&'static str, String)>,
    /// SMPL joints no BVH joint drives (they follow their parent).
    pub unmapped: Vec<&'static str>,
    /// BVH joints with no SMPL counterpart.
    pub dropped: Vec<String>,
    /// Frames and rate of the file.
    pub source_frames: usize,
    /// Frames per second of the file.
    pub source_fps: f64,
    /// Metres per file unit used for the root translation.
    pub metres_per_unit: f64,
    /// Where [`Report::metres_per_unit`] came from: `"joint map"` or `"leg length"`.
    pub scale_from: &'static str,
    /// The file's up and forward axes (`+y`, `+z`, ...).
    pub up_axis: String,
    /// See [`Report::up_axis`].
    pub forward_axis: String,
    /// Whether the first frame was a reference pose and was dropped.
    pub reference_frame_dropped: bool,
}

/// A motion retargeted to SMPL at the file's own frame rate, and what was done.
#[derive(Debug, Clone)]
pub struct Retargeted {
    /// SMPL poses and root translations (the pelvis where the capture's root is, scaled).
    pub motion: Motion,
    /// The report.
    pub report: Report,
}

/// The nearest signed coordinate axis of `v`: (index, sign).
fn snap(v: &Vector3<f64>) -> (usize, f64) {
    let i = v.iamax();
    (i, v[i].signum())
}

fn axis_name((i, sign): (usize, f64)) -> String {
    format!(
        "{}{}",
        if sign > 0.0 { '+' } else { '-' },
        ['x', 'y', 'z'][i]
    )
}

/// The rotation taking unit `from` onto unit `to` (a half turn about a perpendicular axis
/// when they are opposite).
fn rotation_between(from: &Vector3<f64>, to: &Vector3<f64>) -> UnitQuaternion<f64> {
    UnitQuaternion::rotation_between(from, to).unwrap_or_else(|| {
        let side = if from.x.abs() < 0.9 {
            Vector3::x()
        } else {
            Vector3::y()
        };
        UnitQuaternion::from_axis_angle(
            &Unit::new_normalize(from.cross(&side)),
            std::f64::consts::PI,
        )
    })
}

/// The capture's rest pose seen through a joint map, beside the shaped body's.
struct RestPoses<'a> {
    bvh: &'a Bvh,
    map: &'a JointMap,
    shaped: &'a ShapedBody,
    /// The capture's rest joint positions, per BVH joint.
    capture: Vec<Vector3<f64>>,
}

impl RestPoses<'_> {
    /// The shaped body's rest joint `j`.
    fn smpl(&self, j: usize) -> Vector3<f64> {
        Vector3::from(self.shaped.joints[j])
    }

    /// The capture's rest position of SMPL joint `j` (a required, so mapped, joint).
    fn at(&self, j: usize) -> Vector3<f64> {
        self.capture[self.map.bvh_joint[j].expect("required joints are mapped")]
    }

    fn fail(&self, problem: String) -> Error {
        Error::Bvh {
            path: self.bvh.path.clone(),
            line: 1,
            problem,
        }
    }
}

/// The file's axes: up from the pelvis to the highest mapped joint of the trunk (`top`), left
/// from the right hip to the left, forward their cross product; `c` turns the file's axes
/// into SMPL's.
struct FileAxes {
    top: usize,
    up: (usize, f64),
    forward: Vector3<f64>,
    c: UnitQuaternion<f64>,
}

fn file_axes(rest: &RestPoses) -> Result<FileAxes> {
    let k = &rest.map.bvh_joint;
    let top = [15, 12, 9, 6, 3]
        .into_iter()
        .find(|&j| k[j].is_some_and(|b| (rest.capture[b] - rest.at(0)).norm() > 0.0))
        .ok_or_else(|| {
            rest.fail("no mapped trunk joint above the pelvis: cannot tell which way is up".into())
        })?;
    let up = snap(&(rest.at(top) - rest.at(0)));
    let left = snap(&(rest.at(1) - rest.at(2)));
    if up.0 == left.0 {
        return Err(rest.fail(format!(
            "the rest pose's up ({}) and left ({}) are the same axis",
            axis_name(up),
            axis_name(left)
        )));
    }
    let unit = |(i, sign): (usize, f64)| {
        let mut v = Vector3::zeros();
        v[i] = sign;
        v
    };
    let (left_v, up_v) = (unit(left), unit(up));
    let forward = left_v.cross(&up_v);
    let c = UnitQuaternion::from_rotation_matrix(&Rotation3::from_matrix_unchecked(
        Matrix3::from_rows(&[left_v.transpose(), up_v.transpose(), forward.transpose()]),
    ));
    Ok(FileAxes {
        top,
        up,
        forward,
        c,
    })
}

/// Metres per unit: the map's, or the SMPL legs over the capture's; with where it came from.
fn scale(rest: &RestPoses) -> Result<(f64, &'static str)> {
    if let Some(m) = rest.map.metres_per_unit {
        return Ok((m, "joint map"));
    }
    let leg = |p: &dyn Fn(usize) -> Vector3<f64>, hip: usize, knee: usize, ankle: usize| {
        (p(hip) - p(knee)).norm() + (p(knee) - p(ankle)).norm()
    };
    let at = |j| rest.at(j);
    let smpl = |j| rest.smpl(j);
    let capture = leg(&at, 1, 4, 7) + leg(&at, 2, 5, 8);
    let body = leg(&smpl, 1, 4, 7) + leg(&smpl, 2, 5, 8);
    if capture <= 0.0 {
        return Err(rest.fail(
            "the capture's legs have zero length: give metres_per_unit in a joint map".into(),
        ));
    }
    Ok((body / capture, "leg length"))
}

/// Per-bone rest alignment A_j (SMPL rest bone -> the capture's, in SMPL axes): the trunk's
/// joints share one; a joint takes its first mapped descendant's bone, else its ancestor's.
fn rest_alignment(rest: &RestPoses, axes: &FileAxes) -> [UnitQuaternion<f64>; NUM_JOINTS] {
    let (k, c, top) = (&rest.map.bvh_joint, axes.c, axes.top);
    let trunk = rotation_between(
        &(rest.smpl(top) - rest.smpl(0)).normalize(),
        &(c * (rest.at(top) - rest.at(0))).normalize(),
    );
    let mut align = [UnitQuaternion::identity(); NUM_JOINTS];
    for j in 1..NUM_JOINTS {
        if TRUNK.contains(&j) {
            align[j] = trunk;
            continue;
        }
        let inherited = rest
            .map
            .mapped_ancestor(j)
            .map_or(UnitQuaternion::identity(), |a| align[a]);
        align[j] = inherited;
        let Some(from) = k[j] else { continue };
        let mut child = BONE_CHILD[j];
        while let Some(d) = child {
            if let Some(to) = k[d] {
                let bone = c * (rest.capture[to] - rest.capture[from]);
                let smpl_bone = rest.smpl(d) - rest.smpl(j);
                if bone.norm() > 1e-9 && smpl_bone.norm() > 1e-9 {
                    align[j] = rotation_between(&smpl_bone.normalize(), &bone.normalize());
                    break;
                }
            }
            child = BONE_CHILD[d];
        }
    }
    align
}

/// Whether frame 0 is a reference pose (a jump past REFERENCE_FRAME_JUMP_DEG to frame 1).
fn reference_frame(bvh: &Bvh, k: &[Option<usize>; NUM_JOINTS]) -> bool {
    bvh.frames() >= 2 && {
        let (a, _) = bvh.pose(0);
        let (b, _) = bvh.pose(1);
        k.iter()
            .flatten()
            .any(|&j| a[j].angle_to(&b[j]).to_degrees() > REFERENCE_FRAME_JUMP_DEG)
    }
}

/// SMPL's pose of capture frame `f`: each mapped joint's world rotation carried into SMPL's
/// axes and rest bones, unmapped joints following their parent; the pelvis translated.
fn frame_pose(
    rest: &RestPoses,
    axes: &FileAxes,
    align: &[UnitQuaternion<f64>; NUM_JOINTS],
    metres_per_unit: f64,
    f: usize,
) -> FramePose {
    let (k, c) = (&rest.map.bvh_joint, axes.c);
    let c_inverse = c.inverse();
    let (rotations, positions) = rest.bvh.pose(f);
    let mut world = [UnitQuaternion::identity(); NUM_JOINTS];
    let mut pose = [0.0; POSE_DIM];
    for j in 0..NUM_JOINTS {
        let parent = SMPL_PARENTS[j].map(|p| world[p]);
        world[j] = match k[j] {
            Some(b) => c * rotations[b] * c_inverse * align[j],
            None => parent.unwrap_or_else(UnitQuaternion::identity),
        };
        let local = parent.map_or(world[j], |p| p.inverse() * world[j]);
        pose[3 * j..3 * j + 3].copy_from_slice(&quat_to_axis_angle(&local));
    }
    let pelvis = c * positions[k[0].expect("the pelvis is mapped")] * metres_per_unit;
    FramePose {
        pose,
        transl: (pelvis - rest.smpl(0)).into(),
    }
}

/// Retargets `bvh` through `map` onto the shaped body `shaped` (its rest joints fix the bone
/// directions and the leg length). Stages: the file's axes, the scale, the rest alignment,
/// every frame's pose, the report.
pub fn retarget(bvh: &Bvh, map: &JointMap, shaped: &ShapedBody) -> Result<Retargeted> {
    let rest = RestPoses {
        bvh,
        map,
        shaped,
        capture: bvh.rest_positions(),
    };
    let axes = file_axes(&rest)?;
    let (metres_per_unit, scale_from) = scale(&rest)?;
    let align = rest_alignment(&rest, &axes);
    let k = &map.bvh_joint;
    let reference_frame_dropped = reference_frame(bvh, k);
    let first = usize::from(reference_frame_dropped);
    let frames = (first..bvh.frames())
        .map(|f| frame_pose(&rest, &axes, &align, metres_per_unit, f))
        .collect();
    let motion = Motion::new(bvh.path.display().to_string(), bvh.fps(), frames)?;
    let mapped = (0..NUM_JOINTS)
        .filter_map(|j| k[j].map(|b| (JOINT_NAMES[j], bvh.joints[b].name.clone())))
        .collect();
    let unmapped = (0..NUM_JOINTS)
        .filter(|&j| k[j].is_none())
        .map(|j| JOINT_NAMES[j])
        .collect();
    let dropped = (0..bvh.joints.len())
        .filter(|b| !k.contains(&Some(*b)))
        .map(|b| bvh.joints[b].name.clone())
        .collect();
    Ok(Retargeted {
        motion,
        report: Report {
            map: map.name.clone(),
            mapped,
            unmapped,
            dropped,
            source_frames: bvh.frames(),
            source_fps: bvh.fps(),
            metres_per_unit,
            scale_from,
            up_axis: axis_name(axes.up),
            forward_axis: axis_name(snap(&axes.forward)),
            reference_frame_dropped,
        },
    })
}
