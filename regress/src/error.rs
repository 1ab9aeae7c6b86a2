//! The regression suite's errors: the engine's own (a drape bench value out of range among
//! them), a scenario whose setup check failed, and a golden file that is unreadable or of
//! another shape.

use thiserror::Error;

/// Result with [`Error`].
pub type Result<T, E = Error> = std::result::Result<T, E>;

/// What can go wrong running the suite.
#[derive(Debug, Error)]
pub enum Error {
    /// The engine failed (setup, a solve, a recording).
    #[error(transparent)]
    Sim(#[from] sim::Error),
    /// A body model or motion problem.
    #[error(transparent)]
    Motion(#[from] motions::Error),
    /// A file could not be written or read.
    #[error(transparent)]
    File(#[from] files::Error),
    /// A scenario's own setup check failed.
    #[error("scenario '{scenario}': {problem}")]
    Scenario {
        /// The scenario.
        scenario: &'static str,
        /// What went wrong.
        problem: String,
    },
    /// A golden file that cannot serve (unreadable, or another shape than the re-simulation).
    #[error("golden {path}: {message}")]
    Golden {
        /// The file.
        path: String,
        /// What is wrong.
        message: String,
    },
}

impl Error {
    /// A bad value of `key`, with what is expected (the engine's [`sim::Error::Value`]).
    pub fn value(key: &str, value: impl std::fmt::Display, expected: &str) -> Self {
        Self::Sim(sim::Error::value(key, value, expected))
    }
}
