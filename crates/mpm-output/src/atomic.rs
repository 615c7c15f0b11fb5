//! Atomic file writes: write a temporary file beside the target, then rename it over the
//! target, so that a run killed at any moment leaves only complete files. Time series grow by
//! appends of whole lines instead, one write each: only a run killed inside that write can leave
//! a torn last line, and `mpm resume` rewrites the file from its checkpoint.

use std::io::Write;
use std::path::{Path, PathBuf};

use crate::OutputError;

/// the temporary name used for `path` (same directory, same extension so that writers which
/// pick a format from the extension still work).
pub fn temp_path(path: &Path) -> PathBuf {
    let name = path.file_name().map(|n| n.to_string_lossy().into_owned()).unwrap_or_default();
    let tmp = match name.rsplit_once('.') {
        Some((stem, ext)) => format!(".{stem}.tmp-{}.{ext}", std::process::id()),
        None => format!(".{name}.tmp-{}", std::process::id()),
    };
    path.with_file_name(tmp)
}

/// writes `bytes` to `path` atomically.
pub fn write(path: &Path, bytes: &[u8]) -> Result<(), OutputError> {
    let tmp = temp_path(path);
    std::fs::write(&tmp, bytes).map_err(|source| OutputError::Io { path: tmp.clone(), source })?;
    commit(&tmp, path)
}

/// writes `parts` one after the other to `path` atomically (no copy into one buffer).
pub fn write_parts(path: &Path, parts: &[&[u8]]) -> Result<(), OutputError> {
    let tmp = temp_path(path);
    let io = |source| OutputError::Io { path: tmp.clone(), source };
    let mut file = std::fs::File::create(&tmp).map_err(io)?;
    for part in parts {
        if let Err(source) = file.write_all(part) {
            drop(file);
            let _ = std::fs::remove_file(&tmp);
            return Err(io(source));
        }
    }
    drop(file);
    commit(&tmp, path)
}

/// appends `bytes` (whole lines) to the existing file at `path` with one `write_all`.
pub fn append(path: &Path, bytes: &[u8]) -> Result<(), OutputError> {
    let io = |source| OutputError::Io { path: path.to_path_buf(), source };
    let mut file = std::fs::OpenOptions::new().append(true).open(path).map_err(io)?;
    file.write_all(bytes).map_err(io)
}

/// renames a finished temporary file over its target.
pub fn commit(tmp: &Path, path: &Path) -> Result<(), OutputError> {
    std::fs::rename(tmp, path).map_err(|source| {
        let _ = std::fs::remove_file(tmp);
        OutputError::Io { path: path.to_path_buf(), source }
    })
}
