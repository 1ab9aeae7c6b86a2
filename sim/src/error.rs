//! Typed errors of the engine: bad input is reported with what was wrong and where (the key,
//! the vertex, the file, the frame), numerical failure with where it happened. Nothing in the
//! engine panics on user input.

use thiserror::Error;

/// Result with [`Error`].
pub type Result<T, E = Error> = std::result::Result<T, E>;

/// What is wrong with a cloth mesh.
#[derive(Debug, Clone, PartialEq, Error)]
pub enum MeshError {
    /// The mesh has no triangles.
    #[error("no triangles")]
    NoTriangles,
    /// A rest position is NaN or infinite.
    #[error("vertex {vertex} is not finite")]
    NonFiniteVertex {
        /// The vertex.
        vertex: usize,
    },
    /// A triangle refers to a vertex past the end.
    #[error("triangle {triangle} refers to vertex {vertex} but there are {vertices} vertices")]
    MissingVertex {
        /// The triangle.
        triangle: usize,
        /// The index it holds.
        vertex: u32,
        /// Vertices of the mesh.
        vertices: usize,
    },
    /// A triangle repeats a vertex or has no area.
    #[error("triangle {triangle} {corners:?} is degenerate")]
    Degenerate {
        /// The triangle.
        triangle: usize,
        /// Its corners.
        corners: [u32; 3],
    },
    /// A vertex belongs to no triangle.
    #[error("vertex {vertex} is used by no triangle")]
    UnusedVertex {
        /// The vertex.
        vertex: usize,
    },
    /// A generated grid is too small.
    #[error("a grid needs at least 2 x 2 vertices, got {columns} x {rows}")]
    GridTooSmall {
        /// Vertices along one side.
        columns: usize,
        /// Vertices along the other.
        rows: usize,
    },
}

/// What can go wrong when building or running a simulation.
#[derive(Debug, Error)]
pub enum Error {
    /// A file the user named is unreadable, not a regular file or too large, or an output
    /// path holds something that must not be replaced.
    #[error(transparent)]
    File(#[from] files::Error),
    /// The cloth mesh is unusable.
    #[error("invalid cloth mesh: {0}")]
    Mesh(#[from] MeshError),
    /// A configuration value (material, solver or scene setting) is out of range; `key` is its
    /// name in the scene configuration (`material.k_s_n_per_m`, `solver.substeps`, `friction`).
    #[error("{key} = {value}: {expected}")]
    Value {
        /// The key, as written in a scene configuration file.
        key: String,
        /// The value given.
        value: String,
        /// What it must be.
        expected: String,
    },
    /// A constraint of a cloth setup (pin, seam, spring, attachment) refers to a vertex that
    /// does not exist or has an unusable stiffness or length.
    #[error("{kind} {index} is unusable: {problem}")]
    Constraint {
        /// `pin`, `seam`, `spring` or `attachment`.
        kind: &'static str,
        /// Its position in the setup's list.
        index: usize,
        /// What is wrong.
        problem: String,
    },
    /// An obstacle is unusable (non-finite, open mesh, wrong vertex count).
    #[error("obstacle '{obstacle}': {problem}")]
    Obstacle {
        /// Which obstacle (`body`, a prop's name).
        obstacle: String,
        /// What is wrong.
        problem: String,
    },
    /// A motion frame holds a NaN or infinite value.
    #[error("motion '{motion}' frame {frame} has a non-finite value")]
    NonFiniteMotion {
        /// The motion.
        motion: String,
        /// The frame.
        frame: usize,
    },
    /// The motion has no frames.
    #[error("motion '{motion}' has no frames")]
    EmptyMotion {
        /// The motion.
        motion: String,
    },
    /// A built-in garment or a library design's template could not be made.
    #[error("garment '{garment}': {problem}")]
    Garment {
        /// The garment name.
        garment: String,
        /// What went wrong.
        problem: String,
    },
    /// A library design's template, once sewn and settled, failed its quality gates (a
    /// drawn design can: synthesis records its sequences as failed rather than stopping).
    #[error("garment '{garment}': the template failed its quality gates: {failed}")]
    TemplateGates {
        /// The design's name.
        garment: String,
        /// The gates it failed.
        failed: String,
    },
    /// The global matrix could not be factorized (should not happen for valid input).
    #[error("factorization of the global matrix failed ({stage}): {message}")]
    Factorization {
        /// `assembly`, `symbolic` or `numeric`.
        stage: &'static str,
        /// The solver's message.
        message: String,
    },
    /// A frame kept producing non-finite values or exploding energy after every retry.
    #[error(
        "simulation blew up at frame {frame}: {reason} (after {retries} retries with smaller steps)"
    )]
    BlowUp {
        /// Output frame index.
        frame: usize,
        /// What was detected.
        reason: BlowUpCause,
        /// Retries made.
        retries: usize,
    },
    /// A run reached its deadline before its last frame (a typed stop, not a failure of the
    /// engine: dataset synthesis records it as a time-out).
    #[error("time limit reached at frame {frame}")]
    Deadline {
        /// The frame that was about to be handed out.
        frame: usize,
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
    /// A scene configuration file is unreadable, has an unknown key or a value of the wrong
    /// type.
    #[error("scene configuration {path}: {message}")]
    Config {
        /// The file (or `--config-from` recording).
        path: String,
        /// What is wrong (naming the key).
        message: String,
    },
}

impl Error {
    /// An out-of-range value of `key`.
    pub fn value(key: &str, value: impl std::fmt::Display, expected: &str) -> Self {
        Self::Value {
            key: key.to_string(),
            value: value.to_string(),
            expected: expected.to_string(),
        }
    }
}

/// What made the solver give a frame up.
#[derive(Debug, Clone, Copy, PartialEq, Error)]
pub enum BlowUpCause {
    /// A position or velocity became NaN or infinite.
    #[error("non-finite position or velocity")]
    NonFinite,
    /// A vertex moved faster than the solver's limit (energy explosion).
    #[error("vertex {vertex} reached {speed:.1} m/s (limit {limit} m/s): energy explosion")]
    TooFast {
        /// The fastest vertex.
        vertex: usize,
        /// Its speed, m/s.
        speed: f64,
        /// `solver.max_speed`, m/s.
        limit: f64,
    },
}
