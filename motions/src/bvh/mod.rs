//! BVH motion capture (CMU, 100STYLE, LaFAN1, Mixamo exports), read and retargeted to the 24
//! SMPL joints: [`parse`] reads the file, [`joint_map`] says which BVH joint drives each SMPL
//! joint, [`retarget`] turns the capture's rotations into SMPL poses.

pub mod joint_map;
pub mod parse;
pub mod retarget;

use std::path::Path;

pub use joint_map::JointMap;
pub use parse::Bvh;
pub use retarget::{Report, Retargeted, retarget};

use crate::error::Result;
use crate::forward::ShapedBody;

/// Reads a BVH file and retargets it onto `shaped`, through the joint map file `map` or the
/// built-in map that fits the skeleton; the motion is at the file's own rate.
pub fn load(path: &Path, map: Option<&Path>, shaped: &ShapedBody) -> Result<Retargeted> {
    let bvh = Bvh::load(path)?;
    let map = match map {
        Some(file) => JointMap::load(file, &bvh)?,
        None => JointMap::builtin_for(&bvh)?,
    };
    retarget(&bvh, &map, shaped)
}
