//! Checkpoint files (bincode 2 with serde): the solver state, the scene text and the output
//! history, so that `mpm resume DIR` continues a run bit-identically. All bincode use is here.

use std::path::Path;

use serde::{Deserialize, Serialize};

use crate::error::RunError;
use crate::model::SavedState;
use crate::output::atomic;
use crate::run::History;

/// Format version of the checkpoint file; bumped when its layout changes (2: the history
/// carries the output time, the solver state the time step's reference densities).
pub(crate) const FORMAT: u32 = 2;

/// The checkpoint file name inside an output directory.
pub const FILE_NAME: &str = "checkpoint.bin";

/// Refuse checkpoint files claiming more than this many bytes of content (a corrupt length
/// field must not exhaust memory).
const LIMIT: usize = 1 << 34;

/// Everything a checkpoint holds.
#[derive(Clone, Debug, Serialize, Deserialize)]
pub(crate) struct CheckpointFile {
    pub format: u32,
    pub code_version: String,
    pub origin: String,
    pub scene_text: String,
    pub state: SavedState,
    pub history: History,
}

fn config() -> impl bincode::config::Config {
    bincode::config::standard().with_limit::<LIMIT>()
}

/// writes `c` to `path` atomically.
pub(crate) fn write(path: &Path, c: &CheckpointFile) -> Result<(), RunError> {
    let bytes = bincode::serde::encode_to_vec(c, config()).map_err(|e| RunError::Checkpoint {
        path: path.to_path_buf(),
        reason: format!("cannot encode: {e}"),
    })?;
    atomic::write(path, &bytes)
}

/// reads a checkpoint file.
pub(crate) fn read(path: &Path) -> Result<CheckpointFile, RunError> {
    let bytes =
        std::fs::read(path).map_err(|source| RunError::Io { path: path.to_path_buf(), source })?;
    // The format leads the file: read it alone first, so that another layout is named as such.
    match bincode::serde::decode_from_slice::<u32, _>(&bytes, config()) {
        Ok((format, _)) if format != FORMAT => {
            return Err(RunError::Checkpoint {
                path: path.to_path_buf(),
                reason: format!("format {format} but this mpm reads format {FORMAT}"),
            });
        }
        _ => {}
    }
    let (c, _): (CheckpointFile, usize) = bincode::serde::decode_from_slice(&bytes, config())
        .map_err(|e| RunError::Checkpoint {
            path: path.to_path_buf(),
            reason: format!("not a readable mpm checkpoint ({e})"),
        })?;
    Ok(c)
}

/// FNV-1a 64 hash (hex) of a value's bincode bytes: equal for bit-identical values.
pub(crate) fn state_hash<T: Serialize>(value: &T) -> String {
    let bytes =
        bincode::serde::encode_to_vec(value, bincode::config::standard()).unwrap_or_default();
    format!("{:016x}", crate::validate::fnv1a(&bytes))
}
