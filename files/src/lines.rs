//! JSON Lines files (dataset plans and manifests, training logs): one value per line, blank
//! lines skipped, a bad line named by its number.

use std::io::Write;
use std::path::Path;

use serde::Serialize;
use serde::de::DeserializeOwned;

use crate::{Error, Result, limits};

/// Reads a JSON Lines file of `T` (at most [`limits::LINES`] bytes), naming the file and the
/// line of a bad entry.
pub fn read_json_lines<T: DeserializeOwned>(path: &Path, what: &'static str) -> Result<Vec<T>> {
    let text = crate::read_to_string(path, limits::LINES, what)?;
    text.lines()
        .enumerate()
        .filter(|(_, l)| !l.trim().is_empty())
        .map(|(i, l)| {
            serde_json::from_str(l).map_err(|e| Error::Entry {
                path: path.to_path_buf(),
                line: i + 1,
                problem: e.to_string(),
            })
        })
        .collect()
}

/// Writes `values` as JSON Lines, atomically (see [`crate::write_with`]).
pub fn write_json_lines<T: Serialize>(path: &Path, values: &[T]) -> Result<()> {
    crate::write_with(path, |w| {
        for v in values {
            serde_json::to_writer(&mut *w, v)?;
            writeln!(w)?;
        }
        Ok(())
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn lines_round_trip_and_a_bad_line_is_named() {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("a.jsonl");
        write_json_lines(&path, &[1, 2, 3]).unwrap();
        assert_eq!(std::fs::read_to_string(&path).unwrap(), "1\n2\n3\n");
        assert_eq!(read_json_lines::<i32>(&path, "test").unwrap(), [1, 2, 3]);
        std::fs::write(&path, "1\n\n{oops\n").unwrap();
        let message = read_json_lines::<i32>(&path, "test")
            .unwrap_err()
            .to_string();
        assert!(message.contains("line 3"), "{message}");
    }
}
