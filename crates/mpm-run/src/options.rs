//! How a front end asks for a run: [`RunOptions`].

use std::path::PathBuf;
use std::sync::Arc;
use std::sync::atomic::AtomicBool;

use crate::progress::ProgressSink;

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
