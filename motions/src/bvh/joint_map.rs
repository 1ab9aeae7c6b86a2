//! Which BVH joint drives each SMPL joint: built-in maps for the common skeletons, or a user's
//! TOML file for any other.
//!
//! A map file:
//!
//! ```toml
//! # metres_per_unit = 0.01   # optional: the file's length unit; default from the leg length
//! [joints]                   # SMPL joint = BVH joint; SMPL joints left out follow their parent
//! pelvis = "Hips"
//! left_hip = "LeftUpLeg"
//! left_knee = "LeftLeg"
//! ```

use std::path::Path;

use serde::Deserialize;

use crate::bvh::parse::Bvh;
use crate::error::{Error, Result};
use crate::skeleton::{JOINT_NAMES, NUM_JOINTS, joint_index};

/// A built-in map: for each SMPL joint (in index order), the BVH names that may drive it,
/// the first present and unused wins.
struct BuiltinMap {
    name: &'static str,
    names: [&'static [&'static str]; NUM_JOINTS],
}

/// CMU's cgspeed conversion (`Hips`, `LowerBack`, `Spine`, `Spine1`, `LeftArm`, ...), and
/// LaFAN1 and Mixamo exports (`Spine`, `Spine1`, `Spine2`, ..., `mixamorig:` stripped),
/// and BioVision-style skeletons (`Ab`, `Chest`, `LeftCollar`, `LeftShoulder` as the upper arm,
/// `LeftElbow`, ...: 100STYLE, many older captures).
const BUILTIN: [BuiltinMap; 3] = [
    BuiltinMap {
        name: "cmu",
        names: [
            &["Hips"],
            &["LeftUpLeg"],
            &["RightUpLeg"],
            &["LowerBack"],
            &["LeftLeg"],
            &["RightLeg"],
            &["Spine"],
            &["LeftFoot"],
            &["RightFoot"],
            &["Spine1"],
            &["LeftToeBase"],
            &["RightToeBase"],
            &["Neck"],
            &["LeftShoulder"],
            &["RightShoulder"],
            &["Head"],
            &["LeftArm"],
            &["RightArm"],
            &["LeftForeArm"],
            &["RightForeArm"],
            // The palm hangs from `LeftFingerBase` (at the wrist, below `LeftHand`).
            &["LeftFingerBase", "LeftHand"],
            &["RightFingerBase", "RightHand"],
            &["LFingers"],
            &["RFingers"],
        ],
    },
    BuiltinMap {
        name: "mixamo",
        names: [
            &["Hips"],
            &["LeftUpLeg"],
            &["RightUpLeg"],
            &["Spine"],
            &["LeftLeg"],
            &["RightLeg"],
            &["Spine1"],
            &["LeftFoot"],
            &["RightFoot"],
            &["Spine2"],
            &["LeftToeBase", "LeftToe"],
            &["RightToeBase", "RightToe"],
            &["Neck"],
            &["LeftShoulder"],
            &["RightShoulder"],
            &["Head"],
            &["LeftArm"],
            &["RightArm"],
            &["LeftForeArm"],
            &["RightForeArm"],
            &["LeftHand"],
            &["RightHand"],
            &["LeftHandMiddle1", "LeftHandIndex1"],
            &["RightHandMiddle1", "RightHandIndex1"],
        ],
    },
    BuiltinMap {
        name: "biovision",
        names: [
            &["Hips"],
            &["LeftHip"],
            &["RightHip"],
            &["Ab", "Chest"],
            &["LeftKnee"],
            &["RightKnee"],
            &["Chest2", "Chest"],
            &["LeftAnkle"],
            &["RightAnkle"],
            &["Chest4", "Chest3"],
            &["LeftToes", "LeftToe"],
            &["RightToes", "RightToe"],
            &["Neck"],
            &["LeftCollar"],
            &["RightCollar"],
            &["Head"],
            &["LeftShoulder"],
            &["RightShoulder"],
            &["LeftElbow"],
            &["RightElbow"],
            &["LeftWrist"],
            &["RightWrist"],
            &[],
            &[],
        ],
    },
];

/// The fewest SMPL joints a built-in map must find in a file to be chosen for it.
const MIN_BUILTIN_MATCHES: usize = 14;

/// The SMPL joints a map must drive: without them the body cannot be placed or scaled.
const REQUIRED: [usize; 7] = [0, 1, 2, 4, 5, 7, 8];

/// A joint map resolved against one file: the BVH joint driving each SMPL joint.
#[derive(Debug, Clone, PartialEq)]
pub struct JointMap {
    /// Where the map came from: a built-in map's name or the map file.
    pub name: String,
    /// The BVH joint (index into [`Bvh::joints`]) of each SMPL joint, if any.
    pub bvh_joint: [Option<usize>; NUM_JOINTS],
    /// The file's length unit in metres, when the map gives it.
    pub metres_per_unit: Option<f64>,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct MapFile {
    metres_per_unit: Option<f64>,
    joints: std::collections::BTreeMap<String, String>,
}

/// A joint name without an exporter's namespace (`mixamorig:Hips` -> `Hips`).
fn bare(name: &str) -> &str {
    name.rsplit(':').next().unwrap_or(name)
}

impl JointMap {
    /// The built-in map that finds the most SMPL joints in `bvh` (at least
    /// [`MIN_BUILTIN_MATCHES`], the legs and pelvis among them).
    pub fn builtin_for(bvh: &Bvh) -> Result<Self> {
        let best = BUILTIN
            .iter()
            .map(|map| {
                let mut used = vec![false; bvh.joints.len()];
                let bvh_joint: [Option<usize>; NUM_JOINTS] = std::array::from_fn(|j| {
                    let k = map.names[j].iter().find_map(|name| {
                        bvh.joints
                            .iter()
                            .position(|b| bare(&b.name).eq_ignore_ascii_case(name))
                            .filter(|&k| !used[k])
                    })?;
                    used[k] = true;
                    Some(k)
                });
                JointMap {
                    name: map.name.to_string(),
                    bvh_joint,
                    metres_per_unit: None,
                }
            })
            .max_by_key(|m| m.bvh_joint.iter().flatten().count())
            .expect("there are built-in maps");
        let found = best.bvh_joint.iter().flatten().count();
        if found < MIN_BUILTIN_MATCHES || REQUIRED.iter().any(|&j| best.bvh_joint[j].is_none()) {
            let names: Vec<&str> = bvh.joints.iter().map(|j| j.name.as_str()).collect();
            return Err(Error::Bvh {
                path: bvh.path.clone(),
                line: 1,
                problem: format!(
                    "no built-in joint map (cmu, mixamo, biovision) fits this skeleton (best: {} \
                     with {found} of 24 SMPL joints); give one with map=FILE.toml (docs/FORMATS.md, \
                     'BVH joint maps'). Its joints: {}",
                    best.name,
                    names.join(", ")
                ),
            });
        }
        best.check_hierarchy(bvh, &bvh.path)?;
        Ok(best)
    }

    /// Reads a map file and resolves it against `bvh`.
    pub fn load(path: &Path, bvh: &Bvh) -> Result<Self> {
        let text = files::read_to_string(path, files::limits::TEXT, "BVH joint map")?;
        let bad = |problem: String| Error::JointMap {
            path: path.to_path_buf(),
            problem,
        };
        let file: MapFile = toml::from_str(&text).map_err(|e| {
            let line = e
                .span()
                .map_or(1, |s| text[..s.start].matches('\n').count() + 1);
            bad(format!("line {line}: {}", e.message()))
        })?;
        if let Some(m) = file.metres_per_unit
            && !(m.is_finite() && m > 0.0 && m <= 100.0)
        {
            return Err(bad(format!(
                "metres_per_unit = {m} must be a positive length of at most 100 m"
            )));
        }
        let mut bvh_joint = [None; NUM_JOINTS];
        for (smpl, name) in &file.joints {
            let j = joint_index(smpl).ok_or_else(|| {
                bad(format!(
                    "joints.{smpl}: not an SMPL joint ({})",
                    JOINT_NAMES.join(", ")
                ))
            })?;
            let k = bvh.joint(name).ok_or_else(|| {
                bad(format!(
                    "joints.{smpl} = \"{name}\": {} has no such joint",
                    bvh.path.display()
                ))
            })?;
            if let Some(other) = (0..NUM_JOINTS).find(|&o| bvh_joint[o] == Some(k)) {
                return Err(bad(format!(
                    "joints.{smpl} = \"{name}\": that joint already drives {}",
                    JOINT_NAMES[other]
                )));
            }
            bvh_joint[j] = Some(k);
        }
        if let Some(&j) = REQUIRED.iter().find(|&&j| bvh_joint[j].is_none()) {
            return Err(bad(format!(
                "joints.{} is missing: the pelvis, hips, knees and ankles must be mapped",
                JOINT_NAMES[j]
            )));
        }
        let map = JointMap {
            name: path.display().to_string(),
            bvh_joint,
            metres_per_unit: file.metres_per_unit,
        };
        map.check_hierarchy(bvh, path)?;
        Ok(map)
    }

    /// Each mapped SMPL joint's nearest mapped SMPL ancestor must drive a BVH ancestor of its
    /// BVH joint: otherwise the retargeted limbs would hang from the wrong bones.
    fn check_hierarchy(&self, bvh: &Bvh, path: &Path) -> Result<()> {
        for (j, smpl_name) in JOINT_NAMES.iter().enumerate().skip(1) {
            let Some(k) = self.bvh_joint[j] else { continue };
            let Some(ancestor) = self.mapped_ancestor(j) else {
                continue;
            };
            let a = self.bvh_joint[ancestor].expect("mapped");
            let mut up = bvh.joints[k].parent;
            while let Some(p) = up {
                if p == a {
                    break;
                }
                up = bvh.joints[p].parent;
            }
            if up.is_none() {
                return Err(Error::JointMap {
                    path: path.to_path_buf(),
                    problem: format!(
                        "{} -> '{}' is not below {} -> '{}' in the BVH hierarchy",
                        smpl_name, bvh.joints[k].name, JOINT_NAMES[ancestor], bvh.joints[a].name
                    ),
                });
            }
        }
        Ok(())
    }

    /// The nearest SMPL ancestor of `j` that the map drives.
    pub fn mapped_ancestor(&self, j: usize) -> Option<usize> {
        let mut up = crate::skeleton::SMPL_PARENTS[j];
        while let Some(p) = up {
            if self.bvh_joint[p].is_some() {
                return Some(p);
            }
            up = crate::skeleton::SMPL_PARENTS[p];
        }
        None
    }
}
