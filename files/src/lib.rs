//! User-named files, safely. Every loader of the project reads through [`read`] or
//! [`read_to_string`], which refuse what is not a regular file (a FIFO would block, a device
//! such as `/dev/zero` would never end) and anything larger than the caller's limit, before a
//! byte is read. Every output goes through [`Temporary`]: written under a temporary name beside
//! its destination, registered so that [`remove_temporaries`] (called from the signal handler
//! of the command-line program) can delete it, and renamed into place only when complete.
//! [`check_destination`] refuses, before any work, an output path that is anything but a
//! regular file or nothing.
//!
//! [`write_atomic`] and [`write_with`] are that for whole outputs, [`read_json_lines`] and
//! [`write_json_lines`] for JSON Lines, [`sha256_file`] and [`read_verified`] for the checksums
//! manifests record.
//!
//! Written by hand: the standard library has the pieces, no crate puts these checks together.

mod checksum;
mod destination;
mod lines;
mod read;
mod temporary;
mod write;

pub use checksum::{read_verified, sha256_file, sha256_hex};
pub use destination::{Kind, check_destination, check_folder_destination};
pub use lines::{read_json_lines, write_json_lines};
pub use read::{files_with_extensions, open, open_bounded, read, read_to_string};
pub use temporary::{Temporary, remove_temporaries, temporary_name};
pub use write::{create_folder_of, write_atomic, write_fallible, write_json, write_with};

use std::path::PathBuf;

/// What is wrong with a file.
#[derive(Debug, thiserror::Error)]
pub enum Error {
    /// The operating system refused.
    #[error("{path}: {source}")]
    Io {
        /// The file.
        path: PathBuf,
        /// What it said.
        source: std::io::Error,
    },
    /// The path is not a regular file.
    #[error("{path}: is {kind}, not a regular file")]
    NotAFile {
        /// The file.
        path: PathBuf,
        /// What it is.
        kind: Kind,
    },
    /// The file is larger than the reader accepts.
    #[error("{path}: {bytes} bytes, more than the {limit} bytes a {what} may have")]
    TooLarge {
        /// The file.
        path: PathBuf,
        /// Its size.
        bytes: u64,
        /// The limit.
        limit: u64,
        /// What the file was read as.
        what: &'static str,
    },
    /// An output path holds something that must not be replaced.
    #[error("{path}: is {kind}; refusing to replace it (give the path of a new or regular file)")]
    Destination {
        /// The path.
        path: PathBuf,
        /// What is there.
        kind: Kind,
    },
    /// The file's SHA-256 is not the one recorded for it.
    #[error("{path}: does not match {recorded_by}'s checksum (damaged or replaced)")]
    Checksum {
        /// The file.
        path: PathBuf,
        /// What recorded the checksum (a manifest, a checkpoint's checksums file).
        recorded_by: String,
    },
    /// An entry of a JSON Lines file does not parse.
    #[error("{path} line {line}: not a valid entry: {problem}")]
    Entry {
        /// The file.
        path: PathBuf,
        /// Its line, from 1.
        line: usize,
        /// What the parser said.
        problem: String,
    },
    /// The process is stopping on a signal; no new temporary is started.
    #[error("stopping on a signal")]
    Stopping,
}

/// Limits of the files the project reads, bytes: far above any real file of the kind, far
/// below what would exhaust the memory of a machine that reads it.
pub mod limits {
    /// A text file: scene configuration, dataset spec, manifest, run state (64 MiB).
    pub const TEXT: u64 = 64 << 20;
    /// A JSON Lines file: a dataset plan or manifest, a training log (1 GiB).
    pub const LINES: u64 = 1 << 30;
    /// A garment mesh (OBJ) or sewing pattern (JSON) (512 MiB).
    pub const MESH: u64 = 512 << 20;
    /// A NumPy `.npz` or `.npy` file: a body model or a motion (2 GiB).
    pub const ARRAYS: u64 = 2 << 30;
    /// A sequence recording (MCAP) (4 GiB).
    pub const RECORDING: u64 = 4 << 30;
    /// A training tensor shard or weights file (8 GiB).
    pub const TENSORS: u64 = 8 << 30;
}

/// Result with [`Error`].
pub type Result<T, E = Error> = std::result::Result<T, E>;
