//! What an output path may be: a regular file (replaced) or nothing (created); for a folder
//! output, a folder or nothing. Checked before a run starts, so a refusal costs nothing.

use std::path::Path;

use crate::{Error, Result};

/// What is at a path, in words for errors.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Kind {
    /// A regular file.
    File,
    /// A directory.
    Directory,
    /// A symbolic link.
    Symlink,
    /// A named pipe.
    Fifo,
    /// A character device.
    CharDevice,
    /// A block device.
    BlockDevice,
    /// A socket.
    Socket,
}

impl Kind {
    /// The kind of a file's metadata (from `symlink_metadata` for links).
    pub fn of(meta: &std::fs::Metadata) -> Self {
        use std::os::unix::fs::FileTypeExt;
        let t = meta.file_type();
        if t.is_symlink() {
            Kind::Symlink
        } else if t.is_dir() {
            Kind::Directory
        } else if t.is_fifo() {
            Kind::Fifo
        } else if t.is_char_device() {
            Kind::CharDevice
        } else if t.is_block_device() {
            Kind::BlockDevice
        } else if t.is_socket() {
            Kind::Socket
        } else {
            Kind::File
        }
    }
}

impl std::fmt::Display for Kind {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(match self {
            Kind::File => "a regular file",
            Kind::Directory => "a directory",
            Kind::Symlink => "a symbolic link",
            Kind::Fifo => "a FIFO",
            Kind::CharDevice => "a character device",
            Kind::BlockDevice => "a block device",
            Kind::Socket => "a socket",
        })
    }
}

/// What is at `path` without following a link, or `None` for nothing.
fn kind_at(path: &Path) -> Result<Option<Kind>> {
    match std::fs::symlink_metadata(path) {
        Ok(meta) => Ok(Some(Kind::of(&meta))),
        Err(e) if e.kind() == std::io::ErrorKind::NotFound => Ok(None),
        Err(source) => Err(Error::Io {
            path: path.to_path_buf(),
            source,
        }),
    }
}

/// Refuses an output file path that holds anything but a regular file: a directory, a
/// symbolic link, a FIFO, a device or a socket is never replaced.
pub fn check_destination(path: &Path) -> Result<()> {
    match kind_at(path)? {
        None | Some(Kind::File) => Ok(()),
        Some(kind) => Err(Error::Destination {
            path: path.to_path_buf(),
            kind,
        }),
    }
}

/// Refuses an output folder path that holds anything but a folder (or a link to one).
pub fn check_folder_destination(path: &Path) -> Result<()> {
    match kind_at(path)? {
        None | Some(Kind::Directory) => Ok(()),
        Some(Kind::Symlink) if path.is_dir() => Ok(()),
        Some(kind) => Err(Error::Destination {
            path: path.to_path_buf(),
            kind,
        }),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn only_regular_files_and_nothing_are_replaceable() {
        let dir = tempfile::tempdir().unwrap();
        let file = dir.path().join("f");
        std::fs::write(&file, "x").unwrap();
        check_destination(&file).unwrap();
        check_destination(&dir.path().join("new")).unwrap();
        let err = check_destination(dir.path()).unwrap_err().to_string();
        assert!(err.contains("is a directory; refusing"), "{err}");
        let link = dir.path().join("link");
        std::os::unix::fs::symlink(&file, &link).unwrap();
        let err = check_destination(&link).unwrap_err().to_string();
        assert!(err.contains("is a symbolic link"), "{err}");
        let err = check_destination(Path::new("/dev/null"))
            .unwrap_err()
            .to_string();
        assert!(err.contains("is a character device"), "{err}");
    }

    #[test]
    fn folders_take_folders_and_links_to_them() {
        let dir = tempfile::tempdir().unwrap();
        check_folder_destination(dir.path()).unwrap();
        let link = dir.path().join("link");
        std::os::unix::fs::symlink(dir.path(), &link).unwrap();
        check_folder_destination(&link).unwrap();
        let file = dir.path().join("f");
        std::fs::write(&file, "x").unwrap();
        let err = check_folder_destination(&file).unwrap_err().to_string();
        assert!(err.contains("is a regular file"), "{err}");
    }
}
