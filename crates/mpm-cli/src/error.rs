//! Errors of the front end: a run that could not start or stopped (a refused scene is a
//! [`SceneError`], from `mpm-scene`).

use std::path::PathBuf;

use mpm_scene::{RunSummary, SceneError};

/// Why a run did not complete.
#[derive(Debug, thiserror::Error)]
pub enum RunError {
    /// the scene was refused.
    #[error("{0}")]
    Scene(#[from] Box<SceneError>),
    /// the output directory exists and `force` was not given.
    #[error(
        "output directory {} already exists and is not empty; choose another with --out or \
         pass --force to overwrite it",
        .0.display()
    )]
    OutputExists(PathBuf),
    /// another run holds the output directory (its lock file names the process).
    #[error(
        "output directory {} is in use by another mpm run (process {pid}, lock file {}); wait \
         for it, choose another directory with --out, or delete the lock file if no such run is \
         active",
        dir.display(),
        lock.display()
    )]
    Locked {
        /// the directory.
        dir: PathBuf,
        /// its lock file.
        lock: PathBuf,
        /// the holder's process id.
        pid: u32,
    },
    /// a file could not be read or written.
    #[error("{}: {source}", path.display())]
    Io {
        /// the file.
        path: PathBuf,
        /// the cause.
        source: std::io::Error,
    },
    /// the solver stopped with an instability; what was reached has been written.
    #[error("{message}")]
    Solver {
        /// the solver's message (step, particle, position, cause).
        message: String,
        /// the summary written with the error.
        summary: Box<RunSummary>,
    },
    /// a checkpoint could not be read or does not fit its scene.
    #[error("checkpoint {}: {reason}", path.display())]
    Checkpoint {
        /// the checkpoint file.
        path: PathBuf,
        /// what is wrong.
        reason: String,
    },
    /// invalid command-line arguments (exit code 2, like an invalid scene).
    #[error("{0}")]
    Arguments(String),
    /// a thread pool or similar set-up failure.
    #[error("{0}")]
    Setup(String),
}

impl From<SceneError> for RunError {
    fn from(e: SceneError) -> Self {
        RunError::Scene(Box::new(e))
    }
}

impl From<mpm_output::OutputError> for RunError {
    fn from(e: mpm_output::OutputError) -> Self {
        use mpm_output::OutputError as O;
        match e {
            O::Io { path, source } => RunError::Io { path, source },
            O::OutputExists(dir) => RunError::OutputExists(dir),
            O::Locked { dir, lock, pid } => RunError::Locked { dir, lock, pid },
            O::Checkpoint { path, reason } => RunError::Checkpoint { path, reason },
            O::Encode(message) => RunError::Setup(message),
        }
    }
}
