//! Errors of garment loading and building, naming the file and the problem.

use thiserror::Error;

/// Result with [`Error`].
pub type Result<T, E = Error> = std::result::Result<T, E>;

/// What can go wrong with a garment.
#[derive(Debug, Error)]
pub enum Error {
    /// A file the user named is unreadable, not a regular file or too large.
    #[error(transparent)]
    File(#[from] files::Error),
    /// Reading or writing a file failed.
    #[error("{path}: {source}")]
    Io {
        /// The file.
        path: String,
        /// The cause.
        source: std::io::Error,
    },
    /// The file is not a usable mesh.
    #[error("{path}: {message}")]
    Format {
        /// The file.
        path: String,
        /// What is wrong.
        message: String,
    },
    /// The sewing pattern is malformed or inconsistent.
    #[error("invalid sewing pattern: {0}")]
    Pattern(String),
    /// The mesh breaks what the engine and the surrogate rely on ([`crate::Garment::validate`]).
    #[error("invalid garment mesh '{garment}': {problem}")]
    BadMesh {
        /// The garment's name.
        garment: String,
        /// What is wrong.
        problem: String,
    },
    /// The mesh has problems [`crate::check`] does not repair (listed with counts and examples).
    #[error("'{garment}' cannot be repaired: {}", findings.join("; "))]
    Unrepairable {
        /// The garment's name.
        garment: String,
        /// The findings without a repair.
        findings: Vec<String>,
    },
    /// New UVs could not be made for the mesh.
    #[error("'{garment}': UVs could not be unwrapped: {problem}")]
    Unwrap {
        /// The garment's name.
        garment: String,
        /// Why.
        problem: String,
    },
    /// A parameter of a builder or a repair is out of its range.
    #[error("{parameter}: {problem}")]
    BadParameter {
        /// The parameter ("scale", "skirt", "positions").
        parameter: &'static str,
        /// What is wrong.
        problem: String,
    },
    /// No built-in garment of that name.
    #[error("unknown garment '{0}' (built-in garments: {list})", list = crate::builtin_names().join(", "))]
    Unknown(String),
}
