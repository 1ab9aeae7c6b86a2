//! SMPL fits stored as Python pickles, as captures ship them: 4D-Dress's `SMPL/` folder holds
//! one `mesh-fNNNNN_smpl.pkl` per frame (`global_orient` 3, `body_pose` 69, `transl` 3,
//! `betas` 10, NumPy arrays); other tools write one pickle of N frames (`poses` N x 72 or
//! `global_orient` N x 3 with `body_pose` N x 69, `transl` or `trans` N x 3, `betas`).
//!
//! The fits are SMPL's own frame (y up, translation added after posing), so they become a
//! [`Motion`] as they are: no axis change, no placement. The shape is the first frame's
//! `betas`. The files are read by [`crate::pickle`], which runs no code from them; captures
//! are 30 fps unless the motion argument says `fps=`.

use std::path::{Path, PathBuf};

use crate::error::{Error, Result};
use crate::forward::FramePose;
use crate::motion::Motion;
use crate::pickle::{self, Value};
use crate::skeleton::POSE_DIM;

/// Largest pickle read, bytes (a fit is a few kB; a sequence of an hour at 30 fps of 72
/// doubles per frame is 62 MB).
const MAX_PICKLE_BYTES: u64 = 256 << 20;

/// The frame rate of a capture unless told otherwise (4D-Dress records at 30 fps).
pub const DEFAULT_FPS: f64 = 30.0;

/// The pickles of `path`: the file itself, or a folder's `.pkl` files in name order.
pub fn frame_files(path: &Path) -> Result<Vec<PathBuf>> {
    if !path.is_dir() {
        return Ok(vec![path.to_path_buf()]);
    }
    let files = files::files_with_extensions(path, &["pkl"]).map_err(|source| Error::Io {
        path: path.to_path_buf(),
        source,
    })?;
    if files.is_empty() {
        return Err(Error::BadPickle {
            path: path.to_path_buf(),
            problem: "the folder holds no .pkl file (a 4D-Dress take's SMPL/ folder holds one \
                      per frame)"
                .into(),
        });
    }
    Ok(files)
}

/// Loads the fits of `path` (a pickle or a folder of per-frame pickles) at `fps`.
pub fn load(path: &Path, fps: f64) -> Result<Motion> {
    let mut frames = Vec::new();
    let mut betas = None;
    for file in frame_files(path)? {
        let bytes = files::read(&file, MAX_PICKLE_BYTES, "SMPL fit")?;
        let value = pickle::read(&bytes).map_err(|problem| Error::BadPickle {
            path: file.clone(),
            problem,
        })?;
        let fit = Fit::read(&file, &value)?;
        betas.get_or_insert(fit.betas);
        frames.extend(fit.frames);
    }
    let mut motion = Motion::new(path.display().to_string(), fps, frames)?;
    motion.betas = betas;
    Ok(motion)
}

/// The frames and shape of one pickle.
struct Fit {
    frames: Vec<FramePose>,
    betas: Vec<f64>,
}

impl Fit {
    fn read(path: &Path, value: &Value) -> Result<Self> {
        let bad = |key: &str, problem: String| Error::BadArray {
            path: path.to_path_buf(),
            key: key.into(),
            problem,
        };
        if !matches!(value, Value::Dict(_)) {
            return Err(Error::BadPickle {
                path: path.to_path_buf(),
                problem: "not a dict of SMPL parameters".into(),
            });
        }
        let array = |keys: &[&'static str], width: usize| -> Result<Option<Vec<f64>>> {
            let Some((key, found)) = keys.iter().find_map(|k| value.get(k).map(|v| (*k, v))) else {
                return Ok(None);
            };
            let data = match found {
                Value::Array(a) => a.data.clone(),
                Value::List(items) | Value::Tuple(items) => items
                    .iter()
                    .map(|v| match v {
                        Value::Float(f) => Ok(*f),
                        Value::Int(i) => Ok(*i as f64),
                        other => Err(bad(key, format!("holds {other:?}"))),
                    })
                    .collect::<Result<_>>()?,
                other => return Err(bad(key, format!("is {other:?}, not an array"))),
            };
            if data.is_empty() || !data.len().is_multiple_of(width) {
                return Err(bad(
                    key,
                    format!("holds {} values, not N x {width}", data.len()),
                ));
            }
            if let Some(i) = data.iter().position(|v| !v.is_finite()) {
                return Err(bad(key, format!("value {i} is not finite")));
            }
            Ok(Some(data))
        };
        let missing = |key: &str, what: &str| Error::MissingKey {
            path: path.to_path_buf(),
            key: key.into(),
            what: what.into(),
        };
        let poses = match array(&["poses", "pose", "fullpose"], POSE_DIM)? {
            Some(poses) => poses,
            None => {
                let orient = array(&["global_orient", "root_orient"], 3)?
                    .ok_or_else(|| missing("global_orient", "root rotation, axis-angle"))?;
                let body = array(&["body_pose"], POSE_DIM - 3)?
                    .ok_or_else(|| missing("body_pose", "23 joint rotations, axis-angle"))?;
                interleave(&orient, 3, &body, POSE_DIM - 3)
                    .ok_or_else(|| bad("body_pose", "frames differ from global_orient's".into()))?
            }
        };
        let transl = array(&["transl", "trans"], 3)?
            .ok_or_else(|| missing("transl", "root translation, metres"))?;
        let count = poses.len() / POSE_DIM;
        if transl.len() / 3 != count {
            return Err(bad(
                "transl",
                format!("{} frames, the poses {count}", transl.len() / 3),
            ));
        }
        let betas = match value.get("betas") {
            Some(Value::Array(a)) => a.data.iter().take(a.shape.last().copied().unwrap_or(0)),
            _ => return Err(missing("betas", "shape coefficients")),
        }
        .copied()
        .collect();
        let frames = (0..count)
            .map(|k| FramePose {
                pose: std::array::from_fn(|i| poses[k * POSE_DIM + i]),
                transl: std::array::from_fn(|i| transl[k * 3 + i]),
            })
            .collect();
        Ok(Self { frames, betas })
    }
}

/// Rows of `a` (width `wa`) and `b` (width `wb`) side by side, or `None` if their counts differ.
fn interleave(a: &[f64], wa: usize, b: &[f64], wb: usize) -> Option<Vec<f64>> {
    if a.len() / wa != b.len() / wb {
        return None;
    }
    Some(
        a.chunks_exact(wa)
            .zip(b.chunks_exact(wb))
            .flat_map(|(x, y)| x.iter().chain(y).copied())
            .collect(),
    )
}

#[cfg(test)]
mod tests {
    use super::*;

    fn fixtures() -> PathBuf {
        Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/fixtures/pickle")
    }

    #[test]
    fn a_take_folder_is_one_frame_per_pickle_in_name_order() {
        let m = load(&fixtures().join("take/SMPL"), DEFAULT_FPS).unwrap();
        assert_eq!(m.len(), 3);
        assert_eq!(m.fps, 30.0);
        for (k, frame) in m.frames.iter().enumerate() {
            let s = 0.01 * (k + 1) as f64;
            // global_orient, then body_pose: the formula of tools/make_pickle_fixtures.py.
            assert!((frame.pose[2] - 3.0 * s).abs() < 1e-6);
            assert!((frame.pose[3] - 0.1 * s).abs() < 1e-6);
            assert!((frame.pose[71] - 6.9 * s).abs() < 1e-6);
            assert!((frame.transl[1] - (0.9 + s)).abs() < 1e-6);
        }
        let betas = m.betas.unwrap();
        assert_eq!(betas.len(), 10);
        assert!((betas[9] + 1.0).abs() < 1e-6);
    }

    #[test]
    fn a_single_fit_is_a_motion_of_one_frame() {
        let m = load(&fixtures().join("frame_p2_numpy1.pkl"), DEFAULT_FPS).unwrap();
        assert_eq!(m.len(), 1);
        assert!((m.frames[0].pose[0] - 0.01).abs() < 1e-12);
    }

    #[test]
    fn a_motion_argument_names_a_take_folder_with_its_rate() {
        use crate::source::{FileFormat, MotionSource};
        let dir = fixtures().join("take/SMPL");
        let arg = format!("{}:fps=15", dir.display());
        let MotionSource::File(file) = MotionSource::parse(&arg).unwrap() else {
            panic!("{arg} is not a file motion")
        };
        assert_eq!((file.format, file.fps), (FileFormat::SmplFits, Some(15.0)));
        assert_eq!(file.label(), arg);
        let body = crate::BodyModel::default_body();
        let shaped = body.shape(&[]).unwrap();
        // Three frames at 15 fps last 2/15 s: five frames at 30 fps.
        let loaded = MotionSource::File(file).load(&body, &shaped).unwrap();
        assert_eq!(loaded.motion.len(), 5);
        let single = fixtures().join("frame_p5_f64.pkl");
        let parsed = MotionSource::parse(&single.display().to_string()).unwrap();
        assert!(matches!(parsed, MotionSource::File(f) if f.format == FileFormat::SmplFits));
        let bad = format!("{}:fps=0", dir.display());
        assert!(matches!(
            MotionSource::parse(&bad),
            Err(Error::UnknownMotion { .. })
        ));
    }

    #[test]
    fn what_is_not_a_fit_is_refused_naming_the_file_and_key() {
        let e = load(&fixtures().join("mesh_fortran.pkl"), DEFAULT_FPS).unwrap_err();
        assert!(
            matches!(&e, Error::MissingKey { key, .. } if key == "global_orient"),
            "{e}"
        );
        let e = load(&fixtures().join("hostile_system.pkl"), DEFAULT_FPS).unwrap_err();
        assert!(matches!(&e, Error::BadPickle { problem, .. } if problem.contains("os.system")));
        let empty = tempfile::tempdir().unwrap();
        let e = load(empty.path(), DEFAULT_FPS).unwrap_err();
        assert!(matches!(&e, Error::BadPickle { .. }), "{e}");
    }
}
