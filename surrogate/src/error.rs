//! Typed errors of the surrogate: what is wrong with a template's UV layout, an array's shape,
//! a recording or a dataset, naming the file, the key or the index.

use thiserror::Error;

/// What went wrong with a file: an error of its own kind (kept as the source) or words.
pub type Problem = Box<dyn std::error::Error + Send + Sync>;

/// An [`Error::File`] naming `path`, keeping `problem` as its source.
pub(crate) fn file_error(path: &std::path::Path, problem: impl Into<Problem>) -> Error {
    Error::File {
        path: path.display().to_string(),
        problem: problem.into(),
    }
}

/// An [`Error::Value`]: `key = value: expected`.
pub(crate) fn bad_value(key: &str, value: impl std::fmt::Display, expected: &str) -> Error {
    Error::Value {
        key: key.to_string(),
        value: value.to_string(),
        expected: expected.to_string(),
    }
}

/// Result with [`Error`].
pub type Result<T, E = Error> = std::result::Result<T, E>;

/// What can go wrong building geometry images, conditions or training tensors.
#[derive(Debug, Error)]
pub enum Error {
    /// Not a supported resolution.
    #[error("resolution {resolution} is not supported (32, 64 or 128)")]
    Resolution {
        /// The resolution asked for.
        resolution: usize,
    },
    /// The template has no UV triangles.
    #[error("the template has no UVs (a geometry image needs a UV layout)")]
    NoUvs,
    /// A UV triangle refers to a UV corner past the end.
    #[error("UV triangle {triangle} refers to a UV corner past the {uvs} UVs")]
    BadUvTriangle {
        /// The triangle.
        triangle: usize,
        /// UV corners of the template.
        uvs: usize,
    },
    /// A UV coordinate is NaN or infinite.
    #[error("UV corner {corner} is not finite")]
    NonFiniteUv {
        /// The UV corner.
        corner: usize,
    },
    /// The mesh and UV triangle counts differ.
    #[error("{triangles} triangles but {uv_triangles} UV triangles (one per triangle expected)")]
    UvTriangleCount {
        /// Mesh triangles.
        triangles: usize,
        /// UV triangles.
        uv_triangles: usize,
    },
    /// A triangle refers to a vertex past the end.
    #[error("triangle {triangle} refers to a vertex past the {vertices} vertices")]
    BadTriangle {
        /// The triangle.
        triangle: usize,
        /// Vertices of the template.
        vertices: usize,
    },
    /// A vertex belongs to no triangle, so no UV corner gives it a value.
    #[error("vertex {vertex} has no UV corner (it is in no triangle)")]
    VertexWithoutUv {
        /// The vertex.
        vertex: usize,
    },
    /// Per-vertex values of the wrong length.
    #[error("{got} per-vertex values for a template of {expected} vertices")]
    VertexCount {
        /// The template's vertices.
        expected: usize,
        /// Values given.
        got: usize,
    },
    /// An image of the wrong size.
    #[error("an image of {got} texels where {expected} are expected")]
    TexelCount {
        /// R * R.
        expected: usize,
        /// Texels given.
        got: usize,
    },
    /// A file the user named is unreadable, not a regular file or too large, or an output
    /// path holds something that must not be replaced.
    #[error(transparent)]
    Files(#[from] files::Error),
    /// A recording or dataset file is unusable.
    #[error("{path}: {problem}")]
    File {
        /// The file.
        path: String,
        /// What is wrong: the underlying error (a parser's, the file system's) or words.
        #[source]
        problem: Problem,
    },
    /// A configuration file or value is unusable.
    #[error("{path}: {message}")]
    Config {
        /// The file (or what was being configured).
        path: String,
        /// What is wrong, naming the key.
        message: String,
    },
    /// A setting out of range: `key` names it as written (`model.patch`, `training.lr`,
    /// `steps`, `guidance weight`).
    #[error("{key} = {value}: {expected}")]
    Value {
        /// The key.
        key: String,
        /// The value given.
        value: String,
        /// What it must be.
        expected: String,
    },
    /// Scoring one sequence of an evaluation failed.
    #[error("evaluating sequence {id}: {source}")]
    Sequence {
        /// The sequence.
        id: String,
        /// What failed.
        source: Box<Error>,
    },
    /// Training diverged: the loss stopped being a finite number.
    #[error(
        "training diverged: the loss became {loss} at step {step} (a lower training.lr in {config} may help)"
    )]
    Diverged {
        /// The step whose loss was not finite (1-based).
        step: usize,
        /// The loss.
        loss: f64,
        /// The configuration the run was started with.
        config: String,
    },
    /// No dataset folder was given to build tensors from.
    #[error("no dataset folder given")]
    NoDatasets,
    /// A manifest record without a recording file (a sequence that did not finish).
    #[error("sequence {sequence} has no recording")]
    NoRecording {
        /// The sequence's id.
        sequence: String,
    },
    /// A recording without a frame of motion after its settling frames.
    #[error("the sequence of '{garment}' on '{motion}' has no motion frames to score")]
    NothingToScore {
        /// The garment.
        garment: String,
        /// The motion.
        motion: String,
    },
    /// An input that needs the `lbs_residual` target (its skinning) was asked for without it.
    #[error("{what} need the lbs_residual target (they are built on its skinning)")]
    NeedsLbsResidual {
        /// What was asked for ("body inputs", "nearest-body inputs").
        what: &'static str,
    },
    /// A trained model that does not fit the body model, the condition layout or its own
    /// statistics.
    #[error("the model in {run}: {problem}")]
    ModelMismatch {
        /// The run folder.
        run: String,
        /// What does not fit.
        problem: String,
    },
    /// A motion shorter than the model's pose window.
    #[error(
        "the motion '{motion}' has {frames} frames; the model's pose window needs at least {needed}"
    )]
    MotionTooShort {
        /// The motion.
        motion: String,
        /// Its frames.
        frames: usize,
        /// The frames the window needs.
        needed: usize,
    },
    /// Frames asked past the end of the motion (or of its betas).
    #[error("frames up to {end} asked of a motion of {len} frames")]
    FramesOutOfRange {
        /// One past the last frame asked.
        end: usize,
        /// The frames there are.
        len: usize,
    },
    /// The network produced a NaN or infinite vertex.
    #[error(
        "frame {frame}: the model predicted a non-finite vertex (its weights or statistics do not \
         fit this input)"
    )]
    NonFinitePrediction {
        /// The frame.
        frame: usize,
    },
    /// A tensor could not be read back as numbers (burn's `DataError`, in words).
    #[error("{what}: {problem}")]
    TensorData {
        /// Which tensor.
        what: &'static str,
        /// burn's error.
        problem: String,
    },
    /// A garment that cannot be prepared for the network (the cause kept as the source).
    #[error("garment '{garment}': {source}")]
    GarmentInput {
        /// The garment's name.
        garment: String,
        /// Why.
        source: Box<Error>,
    },
    /// An imported mesh too coarse to split for the engine without passing its vertex budget.
    #[error(
        "'{garment}': its edges (median {median_edge_cm:.1} cm) are too long for the engine and \
         splitting them would pass {max_vertices} vertices"
    )]
    TooCoarse {
        /// The garment's name.
        garment: String,
        /// Its median edge length, cm.
        median_edge_cm: f64,
        /// The engine's vertex budget.
        max_vertices: usize,
    },
    /// A garment mesh that cannot be used.
    #[error(transparent)]
    Garment(#[from] garments::Error),
    /// An engine error (recordings, metrics).
    #[error(transparent)]
    Sim(#[from] sim::Error),
    /// A dataset problem (from the `dataset` crate).
    #[error(transparent)]
    Dataset(#[from] dataset::Error),
    /// A body model or motion error.
    #[error(transparent)]
    Motion(#[from] motions::Error),
    /// A picture could not be drawn or written.
    #[error(transparent)]
    Render(#[from] render::Error),
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_file_error_keeps_its_cause_as_the_source() {
        let dir = tempfile::tempdir().unwrap();
        let manifest = dir.path().join("manifest.json");
        std::fs::write(&manifest, "{ not json").unwrap();
        let e = crate::data::TrainingTensors::open(dir.path()).unwrap_err();
        assert!(matches!(&e, Error::File { path, .. } if *path == manifest.display().to_string()));
        let source = std::error::Error::source(&e).expect("the parser's error is kept");
        assert!(source.downcast_ref::<serde_json::Error>().is_some());
        // Words are a source too, and the message is the file and the problem.
        let e = file_error(&manifest, "damaged");
        assert_eq!(e.to_string(), format!("{}: damaged", manifest.display()));
        assert_eq!(
            std::error::Error::source(&e).unwrap().to_string(),
            "damaged"
        );
    }
}
