//! What a front end shows of a run while it steps: the library draws nothing itself, and calls
//! a [`Progress`] the caller hands it in [`RunOptions::progress`](crate::RunOptions::progress)
//! (the `mpm` command's bar, a notebook's widget, a log).

use std::fmt;
use std::sync::Arc;

/// Receives a run's progress. Called from the thread that steps the solver, once per step at
/// most, so an implementation should be cheap (throttle redraws itself).
pub trait Progress: Send + Sync {
    /// the run starts (or resumes) at simulated `time` after `steps` steps, to end at `end_time`.
    fn start(&self, end_time: f64, time: f64, steps: u64);
    /// a step ended at simulated `time`, the run's `steps`-th.
    fn update(&self, time: f64, steps: u64);
    /// a warning the user should read (an energy alarm, an interrupt being honoured).
    fn warn(&self, message: &str);
    /// a report line (what the initial-state stage did).
    fn note(&self, message: &str);
    /// the run has ended (clear a bar).
    fn finish(&self);
}

/// An optional, shared [`Progress`]: `None` reports nothing.
#[derive(Clone, Default)]
pub struct ProgressSink(pub Option<Arc<dyn Progress>>);

impl fmt::Debug for ProgressSink {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(if self.0.is_some() { "ProgressSink(Some(..))" } else { "ProgressSink(None)" })
    }
}

impl ProgressSink {
    /// reports to `p`.
    pub fn new(p: impl Progress + 'static) -> Self {
        ProgressSink(Some(Arc::new(p)))
    }

    pub(crate) fn start(&self, end_time: f64, time: f64, steps: u64) {
        if let Some(p) = &self.0 {
            p.start(end_time, time, steps);
        }
    }

    pub(crate) fn update(&self, time: f64, steps: u64) {
        if let Some(p) = &self.0 {
            p.update(time, steps);
        }
    }

    pub(crate) fn warn(&self, message: &str) {
        if let Some(p) = &self.0 {
            p.warn(message);
        }
    }

    pub(crate) fn note(&self, message: &str) {
        if let Some(p) = &self.0 {
            p.note(message);
        }
    }

    pub(crate) fn finish(&self) {
        if let Some(p) = &self.0 {
            p.finish();
        }
    }
}
