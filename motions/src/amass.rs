//! AMASS `.npz` motions (SMPL+H and SMPL-X releases) converted to SMPL-24, y-up, 30 fps.
//!
//! - Poses: `poses[:, :66]` (root and 21 body joints) plus zeros for SMPL's two hand joints;
//!   SMPL-X files with split keys use `root_orient` and `pose_body`. (Taking `poses[:, 3:72]`
//!   is a known bug in some public code: it feeds finger joints in as the hands.)
//! - Frame rate: `mocap_framerate` (SMPL+H) or `mocap_frame_rate` (SMPL-X); a file with
//!   neither is rejected rather than guessed.
//! - AMASS is z-up: the root turns by Rx(-90 deg) and translations become
//!   `R (trans + J0) - J0`, with J0 the shaped pelvis rest joint of the body that will wear the
//!   motion, so the pelvis moves exactly as in the source.
//! - [`write`] is the inverse, for `motions export --out FILE.npz`.

use std::path::Path;

use nalgebra::{UnitQuaternion, Vector3};

use crate::error::{Error, Result};
use crate::forward::FramePose;
use crate::motion::Motion;
use crate::npz::Npz;
use crate::rotation::{axis_angle_to_quat, quat_to_axis_angle};
use crate::skeleton::POSE_DIM;

/// The source frame rates accepted, fps (AMASS files are 60 to 250 fps): outside them a file
/// is damaged, and resampling it would size allocations from the damage.
pub const MIN_SOURCE_FPS: f64 = 1.0;
/// See [`MIN_SOURCE_FPS`].
pub const MAX_SOURCE_FPS: f64 = 1000.0;

/// Loads an AMASS file at its own frame rate, in SMPL-24 y-up form. `pelvis_rest` is J0, the
/// rest pelvis joint of the shaped body that will wear the motion.
pub fn load(path: &Path, pelvis_rest: [f64; 3]) -> Result<Motion> {
    from_npz(Npz::open(path)?, pelvis_rest)
}

/// [`load`] from an archive already open (its path names it in errors and in the motion).
pub fn from_npz<R: std::io::Read + std::io::Seek>(
    mut npz: Npz<R>,
    pelvis_rest: [f64; 3],
) -> Result<Motion> {
    let path = npz.path().to_path_buf();
    let path = path.as_path();
    let fps = frame_rate(&mut npz)?;
    let (count, body) = rotations(&mut npz)?;
    if count == 0 {
        return Err(bad_array(
            path,
            "poses",
            "the sequence is empty (0 frames)".into(),
        ));
    }
    let trans = npz.required(
        "trans",
        &[Some(count), Some(3)],
        "root translation, N x 3, metres",
    )?;
    let pose_array = crate::npz::Array {
        shape: vec![count, 66],
        data: body,
    };
    npz.check_finite("poses", &pose_array)?;
    npz.check_finite("trans", &trans)?;
    let betas = npz.numeric("betas")?.map(|b| b.data);
    let gender = if npz.has("gender") {
        npz.strings("gender")?.and_then(|g| g.into_iter().next())
    } else {
        None
    };

    let z_up_to_y_up =
        UnitQuaternion::from_axis_angle(&Vector3::x_axis(), -std::f64::consts::FRAC_PI_2);
    let j0 = Vector3::from(pelvis_rest);
    let frames = (0..count)
        .map(|i| {
            let src = &pose_array.data[i * 66..(i + 1) * 66];
            let mut pose = [0.0; POSE_DIM];
            pose[..66].copy_from_slice(src);
            let root = z_up_to_y_up * axis_angle_to_quat([src[0], src[1], src[2]]);
            pose[..3].copy_from_slice(&quat_to_axis_angle(&root));
            let t = Vector3::new(
                trans.data[3 * i],
                trans.data[3 * i + 1],
                trans.data[3 * i + 2],
            );
            let transl = z_up_to_y_up * (t + j0) - j0;
            FramePose {
                pose,
                transl: transl.into(),
            }
        })
        .collect();
    let mut motion = Motion::new(path.display().to_string(), fps, frames)?;
    motion.betas = betas;
    motion.gender = gender;
    Ok(motion)
}

/// An error about `key` of the archive at `path`.
fn bad_array(path: &Path, key: &str, problem: String) -> Error {
    Error::BadArray {
        path: path.to_path_buf(),
        key: key.to_string(),
        problem,
    }
}

/// The source frame rate (`mocap_framerate`, or `mocap_frame_rate` in SMPL-X releases).
fn frame_rate<R: std::io::Read + std::io::Seek>(npz: &mut Npz<R>) -> Result<f64> {
    let path = npz.path().to_path_buf();
    let path = path.as_path();
    let fps_array = match npz.numeric("mocap_framerate")? {
        Some(a) => a,
        None => npz.numeric("mocap_frame_rate")?.ok_or_else(|| Error::MissingKey {
            path: path.to_path_buf(),
            key: "mocap_framerate".into(),
            what: "the source frame rate (or 'mocap_frame_rate' in SMPL-X releases); the rate is unknown without it".into(),
        })?,
    };
    let fps = match fps_array.data.as_slice() {
        [v] if (MIN_SOURCE_FPS..=MAX_SOURCE_FPS).contains(v) => *v,
        other => {
            return Err(bad_array(
                path,
                "mocap_framerate",
                format!(
                    "frame rate must be one number from {MIN_SOURCE_FPS} to {MAX_SOURCE_FPS} fps, found {other:?}"
                ),
            ));
        }
    };

    Ok(fps)
}

/// Root and body rotations, N x 66 (from `poses`, or `root_orient` and `pose_body`): the
/// frame count and the values.
fn rotations<R: std::io::Read + std::io::Seek>(npz: &mut Npz<R>) -> Result<(usize, Vec<f64>)> {
    let path = npz.path().to_path_buf();
    let path = path.as_path();
    let rotations = if let Some(poses) = npz.numeric("poses")? {
        if poses.shape.len() != 2 || poses.shape[1] < 66 {
            return Err(bad_array(
                path,
                "poses",
                format!(
                    "shape {:?}, expected (N, 156) for SMPL+H or (N, 165) for SMPL-X",
                    poses.shape
                ),
            ));
        }
        let (n, w) = (poses.shape[0], poses.shape[1]);
        (
            n,
            (0..n)
                .flat_map(|i| poses.data[i * w..i * w + 66].to_vec())
                .collect(),
        )
    } else {
        let root = npz.required(
            "root_orient",
            &[None, Some(3)],
            "root orientation, N x 3 (or 'poses')",
        )?;
        let n = root.shape[0];
        let body = npz.required("pose_body", &[Some(n), Some(63)], "body pose, N x 63")?;
        (
            n,
            (0..n)
                .flat_map(|i| {
                    root.data[i * 3..i * 3 + 3]
                        .iter()
                        .chain(&body.data[i * 63..i * 63 + 63])
                        .copied()
                        .collect::<Vec<_>>()
                })
                .collect(),
        )
    };
    Ok(rotations)
}

/// Writes a 30 fps SMPL motion as an AMASS-style (SMPL+H layout, z up) `.npz`, atomically:
/// `poses` (N x 156: root, 21 body joints, zero hands; SMPL's two hand joints have no place
/// in that layout and are left out), `trans` (N x 3), `betas` (16), `gender` (`neutral`) and
/// `mocap_framerate`. [`load`] with the same `pelvis_rest` reads it back to the same frames.
pub fn write(path: &Path, motion: &Motion, pelvis_rest: [f64; 3], betas: &[f64]) -> Result<()> {
    let y_up_to_z_up =
        UnitQuaternion::from_axis_angle(&Vector3::x_axis(), std::f64::consts::FRAC_PI_2);
    let j0 = Vector3::from(pelvis_rest);
    let count = motion.len() as u64;
    let mut poses = Vec::with_capacity(motion.len() * 156);
    let mut trans = Vec::with_capacity(motion.len() * 3);
    for frame in &motion.frames {
        let p = &frame.pose;
        let root = y_up_to_z_up * axis_angle_to_quat([p[0], p[1], p[2]]);
        poses.extend(quat_to_axis_angle(&root));
        poses.extend(&p[3..66]);
        poses.extend([0.0; 90]);
        let t = y_up_to_z_up * (Vector3::from(frame.transl) + j0) - j0;
        trans.extend([t.x, t.y, t.z]);
    }
    let mut shape = [0.0; 16];
    for (s, b) in shape.iter_mut().zip(betas) {
        *s = *b;
    }
    let arrays: [(&str, &[u64], &[f64]); 4] = [
        ("poses", &[count, 156], &poses),
        ("trans", &[count, 3], &trans),
        ("betas", &[16], &shape),
        ("mocap_framerate", &[], &[motion.fps]),
    ];
    files::write_with(path, |w| {
        let mut npz = npyz::npz::NpzWriter::new(w);
        for (name, shape, data) in arrays {
            crate::npz::write_array(&mut npz, name, shape, data)?;
        }
        crate::npz::write_text(&mut npz, "gender", "neutral")?;
        npz.zip_writer().finish().map_err(std::io::Error::other)?;
        Ok(())
    })?;
    Ok(())
}
