//! A one-line progress bar on stderr, redrawn in place.
//!
//! Hand-rolled rather than `indicatif`: lagc needs one bar with a count and
//! a label, drawn only when stderr is a terminal; twenty lines do that,
//! where indicatif would add a dependency tree (console, unicode-width,
//! number formatting) and a drawing thread for nothing more.

use std::io::Write;

pub struct Progress {
    total: usize,
    done: usize,
    enabled: bool,
}

const WIDTH: usize = 24;

impl Progress {
    /// A bar of `total` steps; draws nothing unless `enabled` (stderr is a
    /// terminal), so logs and tests see no control characters.
    pub fn new(total: usize, enabled: bool) -> Self {
        Progress {
            total: total.max(1),
            done: 0,
            enabled,
        }
    }

    /// Shows that the next step, `label`, is running.
    pub fn start(&mut self, label: &str) {
        if !self.enabled {
            return;
        }
        let filled = WIDTH * self.done / self.total;
        let bar = format!("{}{}", "#".repeat(filled), ".".repeat(WIDTH - filled));
        let mut err = std::io::stderr().lock();
        // `\x1b[K` clears what a longer label left behind.
        let _ = write!(err, "\r[{bar}] {}/{} {label}\x1b[K", self.done, self.total);
        let _ = err.flush();
    }

    pub fn finish_step(&mut self) {
        self.done = (self.done + 1).min(self.total);
    }

    /// Clears the bar's line.
    pub fn clear(&self) {
        if self.enabled {
            let mut err = std::io::stderr().lock();
            let _ = write!(err, "\r\x1b[K");
            let _ = err.flush();
        }
    }
}
