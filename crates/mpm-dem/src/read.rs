//! A raster from a file, the format chosen by its extension. Kept apart from [`Raster`]'s own
//! module so that the formats depend on the raster and the raster on no format.

use std::path::Path;

use crate::error::DemError;
use crate::limits::Budget;
use crate::raster::Raster;
use crate::{ascii, geotiff};

impl Raster {
    /// Reads a raster, choosing the format by the file's extension: `.asc` is an ESRI ASCII
    /// grid, `.tif`/`.tiff` a GeoTIFF.
    pub fn read(path: &Path) -> Result<Self, DemError> {
        Self::read_within(path, None)
    }

    /// [`read`](Self::read) refusing, before allocating, a raster that needs more memory than
    /// `budget` (e.g. what the process may still use).
    pub fn read_within(path: &Path, budget: Budget) -> Result<Self, DemError> {
        let ext = path.extension().and_then(|e| e.to_str()).map(str::to_ascii_lowercase);
        match ext.as_deref() {
            Some("asc") => ascii::read(path, budget),
            Some("tif" | "tiff") => geotiff::read(path, budget),
            _ => Err(DemError::UnknownFormat { file: path.display().to_string() }),
        }
    }

    /// Parses the text of an ESRI ASCII grid; `file` names it in errors.
    pub fn parse_ascii(text: &str, file: &str) -> Result<Self, DemError> {
        ascii::parse(text, file, text.len() as u64, None)
    }
}
