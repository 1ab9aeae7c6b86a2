//! SHA-256 checksums of the files the project writes and checks (dataset recordings, tensor
//! shards, checkpoints, shipped weights), as lowercase hex.

use std::io::Read;
use std::path::Path;

use sha2::{Digest, Sha256};

use crate::{Error, Result};

/// The SHA-256 of `bytes`, lowercase hex.
pub fn sha256_hex(bytes: &[u8]) -> String {
    format!("{:x}", Sha256::digest(bytes))
}

/// The SHA-256 (lowercase hex) and size of a file, read in 1 MiB blocks (a recording need not
/// fit in memory). Never more than the size it had when opened: a growing file still ends.
pub fn sha256_file(path: &Path) -> Result<(String, u64)> {
    let (file, len) = crate::open(path)?;
    let mut file = file.take(len);
    let mut hasher = Sha256::new();
    let mut buffer = vec![0u8; 1 << 20];
    let mut bytes = 0u64;
    loop {
        let n = file.read(&mut buffer).map_err(|source| Error::Io {
            path: path.to_path_buf(),
            source,
        })?;
        if n == 0 {
            break;
        }
        hasher.update(&buffer[..n]);
        bytes += n as u64;
    }
    Ok((format!("{:x}", hasher.finalize()), bytes))
}

/// Reads a file (as [`crate::read`] does) and checks it against the SHA-256 `expected` that
/// `recorded_by` gives for it.
pub fn read_verified(
    path: &Path,
    limit: u64,
    what: &'static str,
    expected: &str,
    recorded_by: &str,
) -> Result<Vec<u8>> {
    let bytes = crate::read(path, limit, what)?;
    if sha256_hex(&bytes) != expected {
        return Err(Error::Checksum {
            path: path.to_path_buf(),
            recorded_by: recorded_by.to_string(),
        });
    }
    Ok(bytes)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_digest_of_known_bytes_and_of_their_file_agree() {
        // FIPS 180-2's "abc".
        let abc = "ba7816bf8f01cfea414140de5dae2223b00361a396177a9cb410ff61f20015ad";
        assert_eq!(sha256_hex(b"abc"), abc);
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("abc");
        std::fs::write(&path, b"abc").unwrap();
        assert_eq!(sha256_file(&path).unwrap(), (abc.to_string(), 3));
        assert_eq!(
            read_verified(&path, 10, "test", abc, "the test").unwrap(),
            b"abc"
        );
        let wrong = read_verified(&path, 10, "test", &sha256_hex(b"abd"), "the manifest");
        let message = wrong.unwrap_err().to_string();
        assert!(
            message.contains("abc") && message.contains("the manifest"),
            "{message}"
        );
    }
}
