//! What a read may take: a regular file only, and the memory a raster may use. Shared by the
//! formats ([`crate::ascii`], [`crate::geotiff`]) and kept apart from the dispatch by extension
//! ([`crate::read`]), so that the formats depend on it and on the raster, never on the dispatch.

use std::path::Path;

use crate::error::DemError;

/// refuses what is not a regular file before it is opened: a FIFO would block the open for
/// ever, a device such as `/dev/zero` would never end.
pub(crate) fn regular_file(path: &Path) -> Result<u64, DemError> {
    let file = || path.display().to_string();
    let meta = std::fs::metadata(path).map_err(|source| DemError::Io { file: file(), source })?;
    if !meta.file_type().is_file() {
        return Err(DemError::Io {
            file: file(),
            source: std::io::Error::other(
                "not a regular file (a directory, a FIFO or a device): give the raster's file",
            ),
        });
    }
    Ok(meta.len())
}

/// The memory a read may use: (bytes, where that limit comes from, for messages), or `None`
/// for no limit beyond [`crate::MAX_CELLS`].
pub type Budget = Option<(u64, &'static str)>;

/// The refusal of a raster that needs `need` bytes of memory beyond the `budget`.
pub(crate) fn too_big(file: &str, size: Option<(u64, u64)>, need: u64, budget: Budget) -> DemError {
    let (room, source) = budget.unwrap_or((0, "the limit"));
    let problem = format!(
        "which need about {:.0} MB of memory to read, but {:.0} MB are available ({source}): \
         crop the raster to the area of the run (e.g. `gdal_translate -projwin`) or coarsen it",
        need as f64 / 1e6,
        room as f64 / 1e6
    );
    match size {
        Some((cols, rows)) => DemError::Size { file: file.into(), cols, rows, problem },
        None => DemError::Io {
            file: file.into(),
            source: std::io::Error::other(format!("the file is {need} bytes long, {problem}")),
        },
    }
}
