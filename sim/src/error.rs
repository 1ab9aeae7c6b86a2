//! Typed errors of the engine: bad input is reported with what was wrong, numerical failure
//! with where it happened. Nothing in the engine panics on user input.

use thiserror::Error;

/// Result with [`Error`].
pub type Result<T, E = Error> = std::result::Result<T, E>;

/// What can go wrong when building or running a simulation.
#[derive(Debug, Error)]
pub enum Error {
    /// The cloth mesh is unusable (empty, bad indices, non-finite or degenerate).
    #[error("invalid cloth mesh: {0}")]
    Mesh(String),
    /// A material value is out of range (must be finite and positive).
    #[error("invalid material: {0}")]
    Material(String),
    /// A solver or scene setting is out of range.
    #[error("invalid setting: {0}")]
    Setting(String),
    /// An obstacle is unusable (non-finite, open body mesh, wrong vertex count).
    #[error("invalid obstacle: {0}")]
    Obstacle(String),
    /// The global matrix could not be factorized (should not happen for valid input).
    #[error("factorization of the global matrix failed: {0}")]
    Factorization(String),
    /// A frame kept producing non-finite values or exploding energy after every retry.
    #[error(
        "simulation blew up at frame {frame}: {reason} (after {retries} retries with smaller steps)"
    )]
    BlowUp {
        /// Output frame index.
        frame: usize,
        /// What was detected.
        reason: String,
        /// Retries made.
        retries: usize,
    },
    /// A body model or motion problem (from the `motions` crate).
    #[error(transparent)]
    Motion(#[from] motions::Error),
    /// Reading or writing a recording failed.
    #[error("recording {path}: {message}")]
    Recording {
        /// The file.
        path: String,
        /// What went wrong.
        message: String,
    },
    /// A dataset spec is unreadable or invalid.
    #[error("dataset spec {path}: {message}")]
    Spec {
        /// The file.
        path: String,
        /// What is wrong (naming the key).
        message: String,
    },
}
