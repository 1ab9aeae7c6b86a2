//! Bodies in motion for the garment engine and the surrogate.
//!
//! - [`BodyModel`]: an SMPL-compatible body model loaded from an SMPL `.npz` file or the
//!   compiled-in licence-free default body ([`BodyModel::default_body`]), with the forward pass
//!   (betas, 72-d axis-angle pose and translation to vertices, joints and joint transforms).
//! - [`Motion`]: a sequence of SMPL poses at a frame rate, from the built-in procedural library
//!   ([`library`]), AMASS files ([`amass`]) or BVH motion capture retargeted to SMPL
//!   ([`bvh`]), named by one argument everywhere ([`MotionSource`]), with time-correct
//!   resampling, blend-in from the canonical A-pose, and the pose windows the surrogate
//!   learns from.
//!
//! Conventions are SMPL's: metres, y up, the body facing +z, +x the body's left, zero pose the
//! T-pose.
#![warn(missing_docs)]

pub mod amass;
mod body_model;
pub mod bvh;
mod error;
pub mod fits;
mod forward;
pub mod library;
mod motion;
pub mod npz;
pub mod pickle;
pub mod rotation;
mod skeleton;
pub mod source;

pub use body_model::{BodyModel, ModelArrays, boundary_edges};
pub use error::{Error, MotionProblem, Result};
pub use forward::{FramePose, PosedBody, ShapedBody, Transform};
pub use motion::{
    BlendIn, MAX_MOTION_FRAMES, MAX_PREFIX_FRAMES, Motion, PoseWindow, canonical_a_pose,
};
pub use skeleton::{
    JOINT_NAMES, NUM_JOINTS, POSE_DIM, POSE_FEATURE_DIM, SMPL_PARENTS, joint_index, mirror_joint,
};
pub use source::{FileFormat, FileMotion, LoadedMotion, MotionSource, place_on_floor, short_label};
