//! Bounded reads of regular files.

use std::io::Read;
use std::path::{Path, PathBuf};

use crate::{Error, Kind, Result};

/// The entries of folder `dir` whose extension is one of `extensions` (any case), in name
/// order: the frames of a capture, the fits of a take.
pub fn files_with_extensions(dir: &Path, extensions: &[&str]) -> std::io::Result<Vec<PathBuf>> {
    let mut files: Vec<PathBuf> = std::fs::read_dir(dir)?
        .filter_map(|entry| entry.ok().map(|e| e.path()))
        .filter(|p| {
            p.extension()
                .is_some_and(|e| extensions.iter().any(|x| e.eq_ignore_ascii_case(x)))
        })
        .collect();
    files.sort();
    Ok(files)
}

/// Opens a regular file for reading, returning it with its size: a directory, FIFO, device
/// or socket is refused before it is opened (opening a FIFO for reading blocks until a writer
/// comes; `/dev/zero` never ends). Symbolic links are followed.
pub fn open(path: &Path) -> Result<(std::fs::File, u64)> {
    let io = |source| Error::Io {
        path: path.to_path_buf(),
        source,
    };
    let not_a_file = |meta: &std::fs::Metadata| Error::NotAFile {
        path: path.to_path_buf(),
        kind: Kind::of(meta),
    };
    let meta = std::fs::metadata(path).map_err(io)?;
    if !meta.is_file() {
        return Err(not_a_file(&meta));
    }
    let file = std::fs::File::open(path).map_err(io)?;
    // Checked again on the open file, in case the path was replaced in between.
    let meta = file.metadata().map_err(io)?;
    if !meta.is_file() {
        return Err(not_a_file(&meta));
    }
    Ok((file, meta.len()))
}

/// [`open`], refusing a file of more than `limit` bytes (`what` names the kind of file in the
/// error), for readers that stream it.
pub fn open_bounded(path: &Path, limit: u64, what: &'static str) -> Result<(std::fs::File, u64)> {
    let (file, len) = open(path)?;
    if len > limit {
        return Err(too_large(path, len, limit, what));
    }
    Ok((file, len))
}

fn too_large(path: &Path, bytes: u64, limit: u64, what: &'static str) -> Error {
    Error::TooLarge {
        path: path.to_path_buf(),
        bytes,
        limit,
        what,
    }
}

/// Reads a whole regular file (see [`open`]) of at most `limit` bytes; `what` names the kind
/// of file in the error.
pub fn read(path: &Path, limit: u64, what: &'static str) -> Result<Vec<u8>> {
    let (file, len) = open_bounded(path, limit, what)?;
    // The file may grow while it is read: never take more than the limit and one byte.
    let mut bytes = Vec::with_capacity(len as usize);
    file.take(limit + 1)
        .read_to_end(&mut bytes)
        .map_err(|source| Error::Io {
            path: path.to_path_buf(),
            source,
        })?;
    if bytes.len() as u64 > limit {
        return Err(too_large(path, bytes.len() as u64, limit, what));
    }
    Ok(bytes)
}

/// [`read`] as UTF-8 text; a leading byte-order mark is dropped (editors on Windows write one).
pub fn read_to_string(path: &Path, limit: u64, what: &'static str) -> Result<String> {
    let bytes = read(path, limit, what)?;
    let text = String::from_utf8(bytes).map_err(|e| Error::Io {
        path: path.to_path_buf(),
        source: std::io::Error::new(
            std::io::ErrorKind::InvalidData,
            format!("not UTF-8 text (byte {})", e.utf8_error().valid_up_to()),
        ),
    })?;
    Ok(match text.strip_prefix('\u{feff}') {
        Some(rest) => rest.to_string(),
        None => text,
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn reads_a_regular_file_and_refuses_a_larger_one() {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("a.txt");
        std::fs::write(&path, "\u{feff}hello").unwrap();
        assert_eq!(read_to_string(&path, 100, "text").unwrap(), "hello");
        let err = read(&path, 4, "text file").unwrap_err().to_string();
        assert!(
            err.contains("8 bytes, more than the 4 bytes a text file may have"),
            "{err}"
        );
    }

    #[test]
    fn refuses_devices_folders_and_links_to_them() {
        let dir = tempfile::tempdir().unwrap();
        let err = read(dir.path(), 100, "text").unwrap_err().to_string();
        assert!(err.contains("is a directory"), "{err}");
        let err = read(Path::new("/dev/zero"), 100, "text")
            .unwrap_err()
            .to_string();
        assert!(err.contains("is a character device"), "{err}");
        let link = dir.path().join("zero");
        std::os::unix::fs::symlink("/dev/zero", &link).unwrap();
        let err = read(&link, 100, "text").unwrap_err().to_string();
        assert!(err.contains("is a character device"), "{err}");
    }

    #[test]
    fn refuses_a_fifo_without_blocking() {
        let dir = tempfile::tempdir().unwrap();
        let fifo = dir.path().join("fifo");
        let made = std::process::Command::new("mkfifo").arg(&fifo).status();
        assert!(
            made.is_ok_and(|s| s.success()),
            "mkfifo (coreutils) makes a FIFO"
        );
        // With no writer, opening it would block forever: the check comes first.
        let err = read(&fifo, 100, "text").unwrap_err().to_string();
        assert!(err.contains("is a FIFO"), "{err}");
    }
}
