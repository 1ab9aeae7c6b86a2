//! Dataset synthesis's errors: a spec, a dataset folder or a shard that cannot serve, named,
//! and the engine's own errors from the sequences it runs.

use thiserror::Error;

/// Result with [`Error`].
pub type Result<T, E = Error> = std::result::Result<T, E>;

/// What can go wrong planning, synthesizing, merging or verifying a dataset.
#[derive(Debug, Error)]
pub enum Error {
    /// The engine failed (a template, a scene, a recording).
    #[error(transparent)]
    Sim(#[from] sim::Error),
    /// A file the user named is unreadable, or an output path is in the way.
    #[error(transparent)]
    File(#[from] files::Error),
    /// A dataset folder is inconsistent or incomplete.
    #[error("dataset {path}: {message}")]
    Dataset {
        /// The folder or file.
        path: String,
        /// What is wrong.
        message: String,
    },
    /// The shard asked for (flag or job-array variables) is malformed or out of range.
    #[error("{0}")]
    Shard(String),
    /// A dataset spec is unreadable or invalid.
    #[error("dataset spec {path}: {message}")]
    Spec {
        /// The file.
        path: String,
        /// What is wrong (naming the key).
        message: String,
    },
}

impl Error {
    /// An out-of-range value of `key` (the engine's [`sim::Error::Value`]).
    pub fn value(key: &str, value: impl std::fmt::Display, expected: &str) -> Self {
        Self::Sim(sim::Error::value(key, value, expected))
    }
}
