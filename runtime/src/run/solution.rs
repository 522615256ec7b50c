//! A whole solution as a value (the generated crates' library API,
//! `solve(...) -> Solution` with `Solution::at(t)`): the continuous
//! extension of every step, kept in order.

pub use crate::method::segment::Segment;
use crate::run::options::{Ending, Outcome};

/// A segment valid up to `until` (an event may end it before its step).
#[derive(Clone, Debug)]
pub struct Piece {
    pub until: f64,
    pub segment: Segment,
}

/// The solution of one run.
#[derive(Clone, Debug)]
pub struct Solution {
    pub t0: f64,
    pub x0: Vec<f64>,
    pub pieces: Vec<Piece>,
    pub outcome: Outcome,
}

impl Solution {
    /// The last time the solution reaches (the span's end, or where `stop
    /// when` ended it).
    pub fn end(&self) -> f64 {
        match self.outcome.ending {
            Ending::Stopped(t) | Ending::Rest { at: t, .. } => t,
            Ending::End => self.pieces.last().map_or(self.t0, |p| p.until),
        }
    }

    /// The state at `t` (clamped to `[t0, end]`).
    pub fn at(&self, t: f64) -> Vec<f64> {
        let mut out = self.x0.clone();
        if t <= self.t0 || self.pieces.is_empty() {
            return out;
        }
        let t = t.min(self.end());
        let i = self.pieces.partition_point(|p| p.until < t);
        let piece = &self.pieces[i.min(self.pieces.len() - 1)];
        piece.segment.eval(t, &mut out);
        out
    }
}
