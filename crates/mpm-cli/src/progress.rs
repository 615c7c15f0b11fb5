//! Progress reporting: an indicatif bar on a terminal (simulated time, steps/s, ETA), plain
//! periodic lines when stderr is not a terminal, nothing when quiet.

use std::io::IsTerminal;
use std::time::{Duration, Instant};

use indicatif::{ProgressBar, ProgressStyle};

/// Time between plain progress lines.
const PLAIN_EVERY: Duration = Duration::from_secs(2);
/// Time between bar redraws.
const BAR_EVERY: Duration = Duration::from_millis(100);
/// The bar counts simulated time in microseconds.
const TICKS_PER_S: f64 = 1e6;

pub(crate) enum Progress {
    Quiet,
    Bar { bar: ProgressBar, last: Instant, start: Instant, steps0: u64 },
    Plain { last: Instant, start: Instant, steps0: u64, end: f64 },
}

impl Progress {
    pub(crate) fn new(quiet: bool, end_time: f64, time: f64, steps: u64) -> Self {
        let now = Instant::now();
        if quiet {
            Progress::Quiet
        } else if std::io::stderr().is_terminal() {
            let bar = ProgressBar::new((end_time * TICKS_PER_S) as u64);
            if let Ok(style) = ProgressStyle::with_template(
                "{bar:40.cyan/blue} {msg} [{elapsed_precise}, ETA {eta}]",
            ) {
                bar.set_style(style.progress_chars("=> "));
            }
            bar.set_position((time * TICKS_PER_S) as u64);
            bar.reset_eta();
            Progress::Bar { bar, last: now, start: now, steps0: steps }
        } else {
            Progress::Plain { last: now, start: now, steps0: steps, end: end_time }
        }
    }

    pub(crate) fn update(&mut self, time: f64, steps: u64) {
        match self {
            Progress::Quiet => {}
            Progress::Bar { bar, last, start, steps0 } => {
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
            Progress::Plain { last, start, steps0, end } => {
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

    /// prints a warning line (above the bar on a terminal); nothing when quiet.
    pub(crate) fn warn(&self, message: &str) {
        match self {
            Progress::Quiet => {}
            Progress::Bar { bar, .. } => bar.println(format!("mpm: warning: {message}")),
            Progress::Plain { .. } => eprintln!("mpm: warning: {message}"),
        }
    }

    pub(crate) fn finish(&mut self) {
        if let Progress::Bar { bar, .. } = self {
            bar.finish_and_clear();
        }
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
