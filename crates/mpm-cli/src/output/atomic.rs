//! Atomic file writes: write a temporary file beside the target, then rename it over the
//! target, so that a run killed at any moment leaves only complete files.

use std::path::{Path, PathBuf};

use crate::error::RunError;

/// the temporary name used for `path` (same directory, same extension so that writers which
/// pick a format from the extension still work).
pub(crate) fn temp_path(path: &Path) -> PathBuf {
    let name = path.file_name().map(|n| n.to_string_lossy().into_owned()).unwrap_or_default();
    let tmp = match name.rsplit_once('.') {
        Some((stem, ext)) => format!(".{stem}.tmp-{}.{ext}", std::process::id()),
        None => format!(".{name}.tmp-{}", std::process::id()),
    };
    path.with_file_name(tmp)
}

/// writes `bytes` to `path` atomically.
pub(crate) fn write(path: &Path, bytes: &[u8]) -> Result<(), RunError> {
    let tmp = temp_path(path);
    std::fs::write(&tmp, bytes).map_err(|source| RunError::Io { path: tmp.clone(), source })?;
    commit(&tmp, path)
}

/// renames a finished temporary file over its target.
pub(crate) fn commit(tmp: &Path, path: &Path) -> Result<(), RunError> {
    std::fs::rename(tmp, path).map_err(|source| {
        let _ = std::fs::remove_file(tmp);
        RunError::Io { path: path.to_path_buf(), source }
    })
}
