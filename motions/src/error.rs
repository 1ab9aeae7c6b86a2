//! Typed errors of the motions crate: every one names the file (or input) and the problem.

use std::path::PathBuf;

/// What went wrong loading or evaluating a body model or a motion.
#[derive(Debug, thiserror::Error)]
pub enum Error {
    /// A file the user named is unreadable, not a regular file or too large.
    #[error(transparent)]
    File(#[from] files::Error),
    /// The file could not be opened or read.
    #[error("{path}: {source}")]
    Io {
        /// The file.
        path: PathBuf,
        /// The underlying I/O error.
        source: std::io::Error,
    },
    /// A pickled SMPL model was given; it must be converted to .npz first.
    #[error(
        "{path}: this is a Python pickle; SMPL .pkl files are not read directly. Convert it once \
         to .npz (see docs/FORMATS.md, 'Converting SMPL .pkl'): load it with chumpy installed, \
         turn every array into a plain numpy array (J_regressor: .toarray()), and np.savez it"
    )]
    Pickle {
        /// The file.
        path: PathBuf,
    },
    /// A pickle of SMPL fits that cannot be read (damaged, or it would run code).
    #[error("{path}: {problem}")]
    BadPickle {
        /// The file (or folder).
        path: PathBuf,
        /// What is wrong.
        problem: String,
    },
    /// The file is not a valid .npz (zip of .npy arrays).
    #[error("{path}: not a readable .npz archive: {reason}")]
    NotNpz {
        /// The file.
        path: PathBuf,
        /// Why.
        reason: String,
    },
    /// A required array is missing.
    #[error("{path}: missing key '{key}' ({what})")]
    MissingKey {
        /// The file.
        path: PathBuf,
        /// The missing key.
        key: String,
        /// What the key should hold.
        what: String,
    },
    /// An array has the wrong shape or type, or holds invalid values.
    #[error("{path}: key '{key}': {problem}")]
    BadArray {
        /// The file.
        path: PathBuf,
        /// The array's key.
        key: String,
        /// What is wrong with it.
        problem: String,
    },
    /// A BVH file is damaged or cannot be retargeted; `line` is where (1 for the whole file).
    #[error("{path}: line {line}: {problem}")]
    Bvh {
        /// The file.
        path: PathBuf,
        /// The line at fault, 1-based.
        line: usize,
        /// What is wrong there.
        problem: String,
    },
    /// A BVH joint map file is malformed or does not fit the BVH file.
    #[error("{path}: {problem}")]
    JointMap {
        /// The map file.
        path: PathBuf,
        /// What is wrong.
        problem: String,
    },
    /// A value given to a computation (a beta, a pose or translation component) is NaN or
    /// infinite.
    #[error("{what} {index} is not finite")]
    NotFinite {
        /// What the value is ("beta", "pose/translation value").
        what: &'static str,
        /// Its index in the input.
        index: usize,
    },
    /// A motion cannot be built or resampled as asked.
    #[error("motion '{name}': {problem}")]
    BadMotion {
        /// The motion's name.
        name: String,
        /// What is wrong.
        problem: MotionProblem,
    },
    /// A frame index past the motion's end.
    #[error("frame {frame} is past the motion's {len} frames")]
    FrameOutOfRange {
        /// The frame asked for.
        frame: usize,
        /// The motion's length in frames.
        len: usize,
    },
    /// Body-model arrays that do not fit SMPL's layout (sizes, parents, weights, values).
    #[error("the body model's arrays are inconsistent: {0}")]
    BadModel(String),
    /// A motion name or specification is not known or malformed.
    #[error("unknown motion '{name}': {reason}")]
    UnknownMotion {
        /// The name given.
        name: String,
        /// Why it was rejected (and what is available).
        reason: String,
    },
}

/// Why a motion was rejected ([`Error::BadMotion`]).
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum MotionProblem {
    /// The frame rate (given or asked for) is not a positive number.
    #[error("frame rate {0} is not a positive number")]
    FrameRate(f64),
    /// The motion has no frames.
    #[error("it has no frames")]
    NoFrames,
    /// A frame holds a NaN or infinite value.
    #[error("frame {0} holds a non-finite value")]
    NonFiniteFrame(usize),
    /// Resampling would exceed [`crate::MAX_MOTION_FRAMES`].
    #[error(
        "resampled to {fps} fps it would have {frames:.0} frames, more than the {max} a motion \
         may have (an hour at 30 fps)"
    )]
    TooLong {
        /// The rate asked for.
        fps: f64,
        /// The frames it would have.
        frames: f64,
        /// The limit.
        max: usize,
    },
}

/// Result with this crate's [`Error`].
pub type Result<T, E = Error> = std::result::Result<T, E>;
