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
    /// Inputs to a computation are inconsistent (wrong lengths, non-finite values).
    #[error("{0}")]
    Invalid(String),
    /// A motion name or specification is not known or malformed.
    #[error("unknown motion '{name}': {reason}")]
    UnknownMotion {
        /// The name given.
        name: String,
        /// Why it was rejected (and what is available).
        reason: String,
    },
}

/// Result with this crate's [`Error`].
pub type Result<T, E = Error> = std::result::Result<T, E>;
