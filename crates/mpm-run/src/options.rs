//! How a front end asks for a run: [`RunOptions`].

use std::path::PathBuf;
use std::sync::Arc;
use std::sync::atomic::AtomicBool;

use crate::error::RunError;
use crate::progress::ProgressSink;

/// The most worker threads a run takes (a pool is started before any work: a mistyped count
/// would otherwise start that many threads).
pub const MAX_THREADS: usize = 4096;

/// the worker threads a run may use: `threads`, or one per core when it is `None`; refused
/// outside 1..=[`MAX_THREADS`] (0 would otherwise be taken silently as one).
pub fn available_threads(threads: Option<usize>) -> Result<usize, RunError> {
    match threads {
        None => Ok(rayon::current_num_threads().max(1)),
        Some(n) if (1..=MAX_THREADS).contains(&n) => Ok(n),
        Some(n) => Err(RunError::Arguments(format!(
            "threads = {n}: give 1 to {MAX_THREADS} worker threads, or leave it out for one per core"
        ))),
    }
}

/// How to run a scene.
#[derive(Clone, Debug, Default)]
pub struct RunOptions {
    /// output directory; `None` writes nothing (the summary is still returned).
    pub out_dir: Option<PathBuf>,
    /// rayon threads; `None` uses rayon's default (one per core).
    pub threads: Option<usize>,
    /// where progress, warnings and reports go; the default reports nothing.
    pub progress: ProgressSink,
    /// overwrite an existing, non-empty output directory.
    pub force: bool,
    /// stop (as on Ctrl-C, writing a checkpoint) after the first step that reaches this
    /// simulated time (s).
    pub stop_after: Option<f64>,
    /// set to true (e.g. by a Ctrl-C handler) to stop after the current step with a checkpoint.
    pub interrupt: Option<Arc<AtomicBool>>,
}
