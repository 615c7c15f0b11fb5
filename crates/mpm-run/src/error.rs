//! Errors of the front end: a run that could not start or stopped (a refused scene is a
//! [`SceneError`], from `mpm-scene`).

use mpm_output::OutputError;
use mpm_scene::{RunSummary, SceneError};

/// Why a run did not complete.
#[derive(Debug, thiserror::Error)]
pub enum RunError {
    /// the scene was refused.
    #[error("{0}")]
    Scene(#[from] Box<SceneError>),
    /// an output file, the output directory or a checkpoint (`mpm-output`).
    #[error(transparent)]
    Output(#[from] OutputError),
    /// the solver stopped with an instability; what was reached has been written.
    #[error("{message}")]
    Solver {
        /// the solver's message (step, particle, position, cause).
        message: String,
        /// the summary written with the error.
        summary: Box<RunSummary>,
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
