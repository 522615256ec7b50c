//! Progress of long runs on stderr: shown only when stderr is a terminal
//! and the run has taken more than a second, redrawn at most ten times a
//! second, erased at the end.

use std::io::{IsTerminal, Write};
use std::time::{Duration, Instant};

pub struct Progress {
    /// When the run started; `None` when progress is not shown (no clock
    /// read for a solve that shows nothing).
    start: Option<Instant>,
    last: Option<Instant>,
    t0: f64,
    t1: f64,
}

impl Progress {
    pub fn new(wanted: bool, t0: f64, t1: f64) -> Progress {
        Progress {
            start: (wanted && std::io::stderr().is_terminal()).then(Instant::now),
            last: None,
            t0,
            t1,
        }
    }

    /// After each step: nothing unless progress is shown (inlined, so that
    /// a run that shows none pays a test a step, not a call).
    #[inline]
    pub fn update(&mut self, t: f64) {
        if let Some(start) = self.start {
            self.redraw(start, t);
        }
    }

    #[cold]
    #[inline(never)]
    fn redraw(&mut self, start: Instant, t: f64) {
        let now = Instant::now();
        if now.duration_since(start) < Duration::from_secs(1) {
            return;
        }
        if self
            .last
            .is_some_and(|l| now.duration_since(l) < Duration::from_millis(100))
        {
            return;
        }
        self.last = Some(now);
        let fraction = ((t - self.t0) / (self.t1 - self.t0)).clamp(0.0, 1.0);
        let mut err = std::io::stderr().lock();
        let _ = write!(
            err,
            "\r  t = {t:.6e} of {:.6e} ({:5.1} %), {:.1} s ",
            self.t1,
            100.0 * fraction,
            now.duration_since(start).as_secs_f64()
        );
        let _ = err.flush();
    }

    pub fn finish(&mut self) {
        if self.start.is_some() && self.last.is_some() {
            let mut err = std::io::stderr().lock();
            let _ = write!(err, "\r{:60}\r", "");
            let _ = err.flush();
        }
    }
}
