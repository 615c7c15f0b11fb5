//! The command's [`Progress`]: an indicatif bar on a terminal (simulated time, steps/s, ETA),
//! plain periodic lines when stderr is not a terminal, nothing when quiet.

use std::io::IsTerminal;
use std::sync::Mutex;
use std::time::{Duration, Instant};

use indicatif::{ProgressBar, ProgressStyle};
use mpm_run::{Progress, ProgressSink};

/// Time between plain progress lines.
const PLAIN_EVERY: Duration = Duration::from_secs(2);
/// Time between bar redraws.
const BAR_EVERY: Duration = Duration::from_millis(100);
/// The bar counts simulated time in microseconds.
const TICKS_PER_S: f64 = 1e6;

/// The state of the terminal's report; `Quiet` until a run starts.
enum State {
    Quiet,
    Bar { bar: ProgressBar, last: Instant, start: Instant, steps0: u64 },
    Plain { last: Instant, start: Instant, steps0: u64, end: f64 },
}

/// Progress on stderr; `mpm run --quiet` has none at all.
pub(crate) struct Terminal(Mutex<State>);

impl Terminal {
    /// the sink of `mpm run` and `mpm resume`: nothing when quiet.
    pub(crate) fn sink(quiet: bool) -> ProgressSink {
        if quiet {
            ProgressSink::default()
        } else {
            ProgressSink::new(Terminal(Mutex::new(State::Quiet)))
        }
    }

    fn with(&self, f: impl FnOnce(&mut State)) {
        // A poisoned lock means a panic elsewhere already reported; keep drawing.
        let mut g = self.0.lock().unwrap_or_else(std::sync::PoisonError::into_inner);
        f(&mut g);
    }
}

impl State {
    fn new(end_time: f64, time: f64, steps: u64) -> Self {
        let now = Instant::now();
        if std::io::stderr().is_terminal() {
            let bar = ProgressBar::new((end_time * TICKS_PER_S) as u64);
            if let Ok(style) = ProgressStyle::with_template(
                "{bar:40.cyan/blue} {msg} [{elapsed_precise}, ETA {eta}]",
            ) {
                bar.set_style(style.progress_chars("=> "));
            }
            bar.set_position((time * TICKS_PER_S) as u64);
            bar.reset_eta();
            State::Bar { bar, last: now, start: now, steps0: steps }
        } else {
            State::Plain { last: now, start: now, steps0: steps, end: end_time }
        }
    }

    fn update(&mut self, time: f64, steps: u64) {
        match self {
            State::Quiet => {}
            State::Bar { bar, last, start, steps0 } => {
                if last.elapsed() >= BAR_EVERY {
                    *last = Instant::now();
                    let rate = (steps - *steps0) as f64 / start.elapsed().as_secs_f64().max(1e-9);
                    bar.set_position((time * TICKS_PER_S) as u64);
                    bar.set_message(format!(
                        "t = {} s, step {steps}, {rate:.0} steps/s",
                        seconds(time)
                    ));
                }
            }
            State::Plain { last, start, steps0, end } => {
                if last.elapsed() >= PLAIN_EVERY {
                    *last = Instant::now();
                    let elapsed = start.elapsed().as_secs_f64();
                    let rate = (steps - *steps0) as f64 / elapsed.max(1e-9);
                    eprintln!(
                        "mpm: t = {} s of {} s ({:.0} %), step {steps}, {rate:.0} steps/s",
                        seconds(time),
                        seconds(*end),
                        100.0 * time / *end
                    );
                }
            }
        }
    }

    /// prints a line (above the bar on a terminal).
    fn println(&self, line: String) {
        match self {
            State::Bar { bar, .. } => bar.println(line),
            State::Quiet | State::Plain { .. } => eprintln!("{line}"),
        }
    }
}

impl Progress for Terminal {
    fn start(&self, end_time: f64, time: f64, steps: u64) {
        self.with(|s| *s = State::new(end_time, time, steps));
    }

    fn update(&self, time: f64, steps: u64) {
        self.with(|s| s.update(time, steps));
    }

    fn warn(&self, message: &str) {
        self.with(|s| s.println(format!("mpm: warning: {message}")));
    }

    fn note(&self, message: &str) {
        self.with(|s| s.println(message.to_string()));
    }

    fn finish(&self) {
        self.with(|s| {
            if let State::Bar { bar, .. } = s {
                bar.finish_and_clear();
            }
        });
    }
}

/// a time in seconds for a progress line: 4 decimals in the usual range, else scientific (an
/// end time of 1e-300 s must not print 300 zeros).
pub(crate) fn seconds(t: f64) -> String {
    if t == 0.0 || (1e-3..1e7).contains(&t.abs()) { format!("{t:.4}") } else { format!("{t:.4e}") }
}

#[cfg(test)]
mod tests {
    #[test]
    fn times_print_compactly_at_any_magnitude() {
        assert_eq!(super::seconds(1.25), "1.2500");
        assert_eq!(super::seconds(0.0), "0.0000");
        assert_eq!(super::seconds(1e-300), "1.0000e-300");
        assert_eq!(super::seconds(3e9), "3.0000e9");
    }
}
