//! The files a granular MPM run writes, for any front end (the `mpm` command, `cargo xtask`,
//! bindings): nothing here steps a solver or decides when to write.
//!
//! - [`vtk`]: particle frames (`.vtp`, ASCII, raw or zlib-compressed binary) and their ParaView
//!   collection (`.pvd`);
//! - [`csv`]: the energy, probe and runout time series;
//! - [`plots`]: PNG charts (plotters, with an embedded font: no system font needed), the
//!   project's one chart module; [`report`] lays out a run's plots with it;
//! - [`checkpoint`]: the checkpoint file (header, checksum, bincode 2: all bincode use is
//!   there) and the output history it carries;
//! - [`dir`]: the output directory (one run at a time, `--force` removes only what a run
//!   wrote); [`atomic`]: writes that never leave a half-written file under the final name.

use std::path::PathBuf;

pub mod atomic;
pub mod checkpoint;
pub mod csv;
pub mod dir;
pub mod loads;
pub mod mapfig;
pub mod maps;
pub mod outline;
pub mod plots;
pub mod report;
pub mod vtk;

/// Why an output file could not be written or read.
#[derive(Debug, thiserror::Error)]
pub enum OutputError {
    /// a file could not be read or written.
    #[error("{}: {source}", path.display())]
    Io {
        /// the file.
        path: PathBuf,
        /// the cause.
        source: std::io::Error,
    },
    /// the output directory exists and is not empty, and removing an earlier run's files was
    /// not asked for.
    #[error(
        "output directory {} already exists and is not empty; choose another (--out, or out= in \
         Python) or pass --force (force=True in Python) to overwrite it",
        .0.display()
    )]
    OutputExists(PathBuf),
    /// another run holds the output directory (its lock file names the process).
    #[error(
        "output directory {} is in use by another mpm run ({}, lock file {}); wait for it, \
         choose another directory with --out, or delete the lock file if no such run is active",
        dir.display(),
        pid.map_or("a lock naming no process yet: a run may be starting, and it is taken as \
                    stale 2 s after it was written".to_string(), |p| format!("process {p}")),
        lock.display()
    )]
    Locked {
        /// the directory.
        dir: PathBuf,
        /// its lock file.
        lock: PathBuf,
        /// the holder's process id (`None`: the lock is empty or garbled, and young).
        pid: Option<u32>,
    },
    /// a state could not be encoded (a fault of this program, not of its input).
    #[error("{0}")]
    Encode(String),
    /// a checkpoint could not be read or does not fit its scene.
    #[error("checkpoint {}: {reason}", path.display())]
    Checkpoint {
        /// the checkpoint file.
        path: PathBuf,
        /// what is wrong.
        reason: String,
    },
}
