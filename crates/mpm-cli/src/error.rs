//! Errors of the front end: a scene that cannot run (with its file, line, column, field path,
//! value, admissible range and fix) and a run that stopped.

use std::path::PathBuf;

use crate::summary::RunSummary;

/// Why a scene was refused, before any step ran.
///
/// Displayed as
/// ```text
/// flume.toml:14:22: `materials.sand.friction_angle_deg` = 95: friction angle out of range
///   admissible: 0 ≤ φ < 90 (degrees)
///   fix: ...
/// ```
#[derive(Clone, Debug, PartialEq)]
pub struct SceneError {
    /// the file (or embedded scene) the text came from.
    pub origin: String,
    /// 1-based line, when the field (or its table) is in the text.
    pub line: Option<usize>,
    /// 1-based column (characters).
    pub column: Option<usize>,
    /// dotted field path, e.g. `materials.sand.friction_angle_deg`, `bodies[0].min` ("" for the
    /// whole file).
    pub path: String,
    /// the offending value as written, if there is one.
    pub value: Option<String>,
    /// what is wrong.
    pub problem: String,
    /// what would be admissible.
    pub admissible: String,
    /// how to fix it.
    pub fix: String,
}

impl std::fmt::Display for SceneError {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(f, "{}", self.origin)?;
        if let Some(line) = self.line {
            write!(f, ":{line}")?;
            if let Some(col) = self.column {
                write!(f, ":{col}")?;
            }
        }
        f.write_str(": ")?;
        if !self.path.is_empty() {
            write!(f, "`{}`", self.path)?;
            if let Some(v) = &self.value {
                write!(f, " = {v}")?;
            }
            f.write_str(": ")?;
        }
        write!(f, "{}", self.problem)?;
        if !self.admissible.is_empty() {
            write!(f, "\n  admissible: {}", self.admissible)?;
        }
        if !self.fix.is_empty() {
            write!(f, "\n  fix: {}", self.fix)?;
        }
        Ok(())
    }
}

impl std::error::Error for SceneError {}

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
        dir.join(crate::run::LOCK_FILE).display()
    )]
    Locked {
        /// the directory.
        dir: PathBuf,
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
