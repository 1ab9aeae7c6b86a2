//! Whole outputs written atomically: under a [`Temporary`] name beside the destination,
//! flushed and synced, then renamed into place.

use std::fs::File;
use std::io::{BufWriter, Write};
use std::path::Path;

use crate::{Error, Result, Temporary};

/// Makes the folder `path` goes into, if missing (outputs may name new folders).
pub fn create_folder_of(path: &Path) -> Result<()> {
    match path.parent().filter(|d| !d.as_os_str().is_empty()) {
        Some(dir) => std::fs::create_dir_all(dir).map_err(|source| Error::Io {
            path: dir.to_path_buf(),
            source,
        }),
        None => Ok(()),
    }
}

/// Writes `value` to `path` as pretty JSON and a newline, atomically, its folder made if
/// missing.
pub fn write_json<T: serde::Serialize>(path: &Path, value: &T) -> Result<()> {
    create_folder_of(path)?;
    write_with(path, |w| {
        serde_json::to_writer_pretty(&mut *w, value)?;
        writeln!(w)
    })
}

/// Writes `bytes` to `path` atomically.
pub fn write_atomic(path: &Path, bytes: &[u8]) -> Result<()> {
    write_with(path, |w| w.write_all(bytes))
}

/// Writes `path` through `fill`, atomically: nothing appears at `path` unless `fill` and the
/// sync succeed (the temporary is removed on an error, and by the signal handler).
pub fn write_with(
    path: &Path,
    fill: impl FnOnce(&mut BufWriter<File>) -> std::io::Result<()>,
) -> Result<()> {
    let (tmp, file) = Temporary::create(path)?;
    let io = |source| Error::Io {
        path: tmp.path().to_path_buf(),
        source,
    };
    let mut writer = BufWriter::new(file);
    fill(&mut writer).map_err(io)?;
    let file = writer.into_inner().map_err(|e| io(e.into_error()))?;
    file.sync_all().map_err(io)?;
    tmp.persist()
}

/// [`write_with`] for a `fill` with its own error type: a failed fill's error comes back
/// whole (the write stops and leaves nothing), a failed write as `E::from`.
pub fn write_fallible<E: From<Error>>(
    path: &Path,
    fill: impl FnOnce(&mut BufWriter<File>) -> std::result::Result<(), E>,
) -> std::result::Result<(), E> {
    let mut failure = None;
    let written = write_with(path, |w| {
        fill(w).map_err(|e| {
            failure = Some(e);
            std::io::Error::other("not completed")
        })
    });
    match failure {
        Some(e) => Err(e),
        None => written.map_err(E::from),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn json_goes_into_a_new_folder_pretty_with_a_newline() {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("new/deeper/out.json");
        write_json(&path, &serde_json::json!({"a": [1, 2]})).unwrap();
        let text = std::fs::read_to_string(&path).unwrap();
        assert_eq!(text, "{\n  \"a\": [\n    1,\n    2\n  ]\n}\n");
        let file_as_folder = path.join("below.json");
        assert!(write_json(&file_as_folder, &1).is_err());
    }

    #[test]
    fn a_failed_fill_leaves_nothing_and_a_good_one_replaces_the_file() {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("out.txt");
        std::fs::write(&path, "old").unwrap();
        let failed = write_with(&path, |w| {
            w.write_all(b"half")?;
            Err(std::io::Error::other("stopped"))
        });
        assert!(failed.is_err());
        assert_eq!(std::fs::read_to_string(&path).unwrap(), "old");
        assert_eq!(std::fs::read_dir(dir.path()).unwrap().count(), 1);
        write_atomic(&path, b"new").unwrap();
        assert_eq!(std::fs::read_to_string(&path).unwrap(), "new");
    }

    #[derive(Debug, PartialEq)]
    enum Fill {
        Stopped(u32),
        Write(String),
    }

    impl From<Error> for Fill {
        fn from(e: Error) -> Self {
            Fill::Write(e.to_string())
        }
    }

    #[test]
    fn a_fallible_fill_keeps_its_own_error_and_leaves_nothing() {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("out.txt");
        let failed = write_fallible(&path, |w| {
            w.write_all(b"half")
                .map_err(|e| Fill::Write(e.to_string()))?;
            Err(Fill::Stopped(7))
        });
        assert_eq!(failed, Err(Fill::Stopped(7)));
        assert_eq!(std::fs::read_dir(dir.path()).unwrap().count(), 0);
        let missing = dir.path().join("no/such/folder/out.txt");
        let e = write_fallible(&missing, |_| Ok::<(), Fill>(())).unwrap_err();
        assert!(matches!(e, Fill::Write(_)), "{e:?}");
        write_fallible(&path, |w| {
            w.write_all(b"whole")
                .map_err(|e| Fill::Write(e.to_string()))
        })
        .unwrap();
        assert_eq!(std::fs::read_to_string(&path).unwrap(), "whole");
    }
}
