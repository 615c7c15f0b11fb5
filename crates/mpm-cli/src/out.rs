//! Standard output that a closed pipe cannot crash: `mpm section … | head` and `mpm check` into a
//! reader that has gone away. `println!` panics when a write fails (exit 101); these macros stop
//! writing instead and let the command finish (its files written, its exit code its own), as
//! `head`'s writers expect of a filter. Any other write error is named once on standard error.

use std::io::{ErrorKind, Write};
use std::sync::atomic::{AtomicBool, Ordering};

/// set once a write to standard output has failed: nothing more is written there.
static CLOSED: AtomicBool = AtomicBool::new(false);

/// writes `args` to standard output unless an earlier write failed.
pub fn write(args: std::fmt::Arguments<'_>) {
    if CLOSED.load(Ordering::Relaxed) {
        return;
    }
    let mut out = std::io::stdout().lock();
    if let Err(e) = out.write_fmt(args).and_then(|()| out.flush()) {
        CLOSED.store(true, Ordering::Relaxed);
        if e.kind() != ErrorKind::BrokenPipe {
            // (standard error may be gone too: never panic over a message)
            let _ = writeln!(std::io::stderr(), "mpm: cannot write to standard output: {e}");
        }
    }
}

/// `println!` that a closed standard output cannot crash (`out::write`).
macro_rules! outln {
    () => { $crate::out::write(format_args!("\n")) };
    ($($arg:tt)*) => { $crate::out::write(format_args!("{}\n", format_args!($($arg)*))) };
}

/// `print!` that a closed standard output cannot crash (`out::write`).
macro_rules! out {
    ($($arg:tt)*) => { $crate::out::write(format_args!($($arg)*)) };
}

pub(crate) use {out, outln};
