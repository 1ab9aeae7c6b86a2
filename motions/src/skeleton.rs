//! The SMPL kinematic tree: 24 joints, their names and parents, shared by every body model.

/// Number of SMPL joints.
pub const NUM_JOINTS: usize = 24;
/// Length of an SMPL pose vector: 24 joints x 3 axis-angle components (radians).
pub const POSE_DIM: usize = 72;
/// Length of the pose-blend-shape feature: 23 non-root joints x 9 rotation-matrix entries.
pub const POSE_FEATURE_DIM: usize = 207;

/// SMPL joint names, in index order.
pub const JOINT_NAMES: [&str; NUM_JOINTS] = [
    "pelvis",
    "left_hip",
    "right_hip",
    "spine1",
    "left_knee",
    "right_knee",
    "spine2",
    "left_ankle",
    "right_ankle",
    "spine3",
    "left_foot",
    "right_foot",
    "neck",
    "left_collar",
    "right_collar",
    "head",
    "left_shoulder",
    "right_shoulder",
    "left_elbow",
    "right_elbow",
    "left_wrist",
    "right_wrist",
    "left_hand",
    "right_hand",
];

/// SMPL parents (`None` for the root, the pelvis).
pub const SMPL_PARENTS: [Option<usize>; NUM_JOINTS] = [
    None,
    Some(0),
    Some(0),
    Some(0),
    Some(1),
    Some(2),
    Some(3),
    Some(4),
    Some(5),
    Some(6),
    Some(7),
    Some(8),
    Some(9),
    Some(9),
    Some(9),
    Some(12),
    Some(13),
    Some(14),
    Some(16),
    Some(17),
    Some(18),
    Some(19),
    Some(20),
    Some(21),
];

/// The joint a mirror image through the body's sagittal plane (x -> -x) puts in joint `j`'s
/// place: left and right swapped, the joints on the midline their own.
pub fn mirror_joint(j: usize) -> usize {
    let name = JOINT_NAMES[j];
    let partner = match (name.strip_prefix("left_"), name.strip_prefix("right_")) {
        (Some(rest), _) => format!("right_{rest}"),
        (_, Some(rest)) => format!("left_{rest}"),
        _ => return j,
    };
    joint_index(&partner).expect("every left joint has a right one")
}

/// Index of a joint by its SMPL name.
pub fn joint_index(name: &str) -> Option<usize> {
    JOINT_NAMES.iter().position(|&n| n == name)
}
