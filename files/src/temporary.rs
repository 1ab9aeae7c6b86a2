//! Outputs under a temporary name, registered so that a signal handler can remove them.

use std::fs::File;
use std::path::{Path, PathBuf};
use std::sync::{Mutex, MutexGuard};

use crate::{Error, Result, check_destination};

/// The temporaries of this process that are not yet in place, and whether it is stopping.
struct Registry {
    stopping: bool,
    paths: Vec<PathBuf>,
}

static REGISTRY: Mutex<Registry> = Mutex::new(Registry {
    stopping: false,
    paths: Vec::new(),
});

fn registry() -> MutexGuard<'static, Registry> {
    REGISTRY
        .lock()
        .unwrap_or_else(|poisoned| poisoned.into_inner())
}

/// The temporary name of an output: `<name>.<pid>.tmp` beside it (the process id keeps two
/// runs writing to one folder apart).
pub fn temporary_name(path: &Path) -> PathBuf {
    let mut name = path
        .file_name()
        .map(|n| n.to_os_string())
        .unwrap_or_default();
    name.push(format!(".{}.tmp", std::process::id()));
    path.with_file_name(name)
}

/// Deletes every registered temporary and refuses new ones: for a signal handler, which
/// then ends the process. Returns how many were removed.
pub fn remove_temporaries() -> usize {
    let mut registry = registry();
    registry.stopping = true;
    let paths = std::mem::take(&mut registry.paths);
    for path in &paths {
        remove(path);
    }
    // The lock is released here; later `create` calls see `stopping` and refuse.
    paths.len()
}

fn remove(path: &Path) {
    if path.is_dir() {
        let _ = std::fs::remove_dir_all(path);
    } else {
        let _ = std::fs::remove_file(path);
    }
}

/// An output being written: a file or folder under its temporary name, removed on drop
/// unless [`Temporary::persist`] moved it into place.
#[derive(Debug)]
pub struct Temporary {
    path: PathBuf,
    destination: PathBuf,
    folder: bool,
    in_place: bool,
}

impl Temporary {
    fn start(
        destination: &Path,
        folder: bool,
        make: impl FnOnce(&Path) -> std::io::Result<()>,
    ) -> Result<Self> {
        check_kind(destination, folder)?;
        let path = temporary_name(destination);
        let mut registry = registry();
        if registry.stopping {
            return Err(Error::Stopping);
        }
        // A leftover of a killed run with the same process id.
        remove(&path);
        make(&path).map_err(|source| Error::Io {
            path: path.clone(),
            source,
        })?;
        registry.paths.push(path.clone());
        Ok(Self {
            path,
            destination: destination.to_path_buf(),
            folder,
            in_place: false,
        })
    }

    /// Creates the temporary file of `destination` (which must be a regular file or
    /// nothing), registered; write it through the returned handle, then [`Self::persist`].
    pub fn create(destination: &Path) -> Result<(Self, File)> {
        let mut file = None;
        let temporary = Self::start(destination, false, |path| {
            file = Some(File::create_new(path)?);
            Ok(())
        })?;
        let file = file.expect("created with the temporary");
        Ok((temporary, file))
    }

    /// Creates the temporary folder of `destination`, registered.
    pub fn create_dir(destination: &Path) -> Result<Self> {
        Self::start(destination, true, |path| std::fs::create_dir(path))
    }

    /// The temporary's own path.
    pub fn path(&self) -> &Path {
        &self.path
    }

    /// Moves the temporary into place, replacing a regular file (or, for a folder, an empty
    /// folder) at the destination.
    pub fn persist(mut self) -> Result<()> {
        check_kind(&self.destination, self.folder)?;
        let mut registry = registry();
        std::fs::rename(&self.path, &self.destination).map_err(|source| Error::Io {
            path: self.destination.clone(),
            source,
        })?;
        registry.paths.retain(|p| p != &self.path);
        self.in_place = true;
        Ok(())
    }
}

/// A file destination must be a regular file or nothing; a folder destination a folder or
/// nothing.
fn check_kind(destination: &Path, folder: bool) -> Result<()> {
    if folder {
        crate::check_folder_destination(destination)
    } else {
        check_destination(destination)
    }
}

impl Drop for Temporary {
    fn drop(&mut self) {
        if !self.in_place {
            let mut registry = registry();
            remove(&self.path);
            registry.paths.retain(|p| p != &self.path);
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::io::Write;

    #[test]
    fn a_persisted_file_is_in_place_and_a_dropped_one_is_gone() {
        let dir = tempfile::tempdir().unwrap();
        let out = dir.path().join("out.json");
        let (tmp, mut file) = Temporary::create(&out).unwrap();
        file.write_all(b"{}").unwrap();
        assert!(tmp.path().exists() && !out.exists());
        tmp.persist().unwrap();
        assert_eq!(std::fs::read(&out).unwrap(), b"{}");
        let (tmp, _file) = Temporary::create(&out).unwrap();
        let path = tmp.path().to_path_buf();
        drop(tmp);
        assert!(!path.exists());
        assert_eq!(std::fs::read(&out).unwrap(), b"{}");
    }

    #[test]
    fn a_destination_that_is_not_a_file_is_refused_before_anything_is_written() {
        let dir = tempfile::tempdir().unwrap();
        let err = Temporary::create(dir.path()).unwrap_err().to_string();
        assert!(err.contains("is a directory"), "{err}");
        let names: Vec<_> = std::fs::read_dir(dir.path()).unwrap().collect();
        assert!(names.is_empty());
    }
}
