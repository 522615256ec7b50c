//! Four independent `f64`s computed together: an ensemble's members four
//! at a time through one right side ([`crate::model::Model::rhs_lanes`]).
//!
//! Every operation is the `f64` operation lane by lane, in the same order
//! (no fused multiply-add, no reassociation), so a lane's value is bit for
//! bit what the scalar code computes for that member; the compiler packs
//! the lanes into SSE2/AVX registers for the arithmetic. Functions without
//! a packed form (`sin`, `exp`, …) are called once per lane: the same libm
//! calls as the scalar code.

use std::ops::{Add, Div, Mul, Neg, Sub};

/// How many members a lane value holds.
pub const WIDTH: usize = 4;

/// Four lanes of `f64`.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
#[repr(C, align(32))]
pub struct Lanes(pub [f64; WIDTH]);

impl Lanes {
    /// Every lane `v`.
    #[inline(always)]
    pub fn splat(v: f64) -> Lanes {
        Lanes([v; WIDTH])
    }

    /// `f` of each lane.
    #[inline(always)]
    pub fn map(self, f: impl Fn(f64) -> f64) -> Lanes {
        let a = self.0;
        Lanes([f(a[0]), f(a[1]), f(a[2]), f(a[3])])
    }

    #[inline(always)]
    fn zip(self, o: Lanes, f: impl Fn(f64, f64) -> f64) -> Lanes {
        let (a, b) = (self.0, o.0);
        Lanes([f(a[0], b[0]), f(a[1], b[1]), f(a[2], b[2]), f(a[3], b[3])])
    }

    #[inline(always)]
    pub fn powi(self, n: i32) -> Lanes {
        self.map(|v| v.powi(n))
    }

    #[inline(always)]
    pub fn powf(self, e: impl Into<Lanes>) -> Lanes {
        self.zip(e.into(), f64::powf)
    }

    #[inline(always)]
    pub fn sqrt(self) -> Lanes {
        self.map(f64::sqrt)
    }

    #[inline(always)]
    pub fn recip(self) -> Lanes {
        self.map(f64::recip)
    }

    #[inline(always)]
    pub fn abs(self) -> Lanes {
        self.map(f64::abs)
    }
}

/// The elementary functions the generated code prints (`Func::name`), lane
/// by lane.
macro_rules! per_lane {
    ($($f:ident)*) => {
        impl Lanes {
            $(
                #[inline(always)]
                pub fn $f(self) -> Lanes {
                    self.map(f64::$f)
                }
            )*
        }
    };
}

per_lane!(sin cos tan asin acos atan sinh cosh tanh exp ln);

impl From<f64> for Lanes {
    #[inline(always)]
    fn from(v: f64) -> Lanes {
        Lanes::splat(v)
    }
}

/// A value the generated lane code assigns to an output: a lane value, or
/// an `f64` the same in every lane (a row that reads no state).
pub trait ToLanes {
    fn to_lanes(self) -> Lanes;
}

impl ToLanes for Lanes {
    #[inline(always)]
    fn to_lanes(self) -> Lanes {
        self
    }
}

impl ToLanes for f64 {
    #[inline(always)]
    fn to_lanes(self) -> Lanes {
        Lanes::splat(self)
    }
}

/// [`ToLanes::to_lanes`] as a function (what generated code calls).
#[inline(always)]
pub fn lanes(v: impl ToLanes) -> Lanes {
    v.to_lanes()
}

macro_rules! binary {
    ($tr:ident $f:ident $op:tt) => {
        impl $tr for Lanes {
            type Output = Lanes;
            #[inline(always)]
            fn $f(self, o: Lanes) -> Lanes {
                let (a, b) = (self.0, o.0);
                Lanes([a[0] $op b[0], a[1] $op b[1], a[2] $op b[2], a[3] $op b[3]])
            }
        }
        impl $tr<f64> for Lanes {
            type Output = Lanes;
            #[inline(always)]
            fn $f(self, o: f64) -> Lanes {
                let a = self.0;
                Lanes([a[0] $op o, a[1] $op o, a[2] $op o, a[3] $op o])
            }
        }
        impl $tr<Lanes> for f64 {
            type Output = Lanes;
            #[inline(always)]
            fn $f(self, o: Lanes) -> Lanes {
                let b = o.0;
                Lanes([self $op b[0], self $op b[1], self $op b[2], self $op b[3]])
            }
        }
    };
}

binary!(Add add +);
binary!(Sub sub -);
binary!(Mul mul *);
binary!(Div div /);

impl Neg for Lanes {
    type Output = Lanes;
    #[inline(always)]
    fn neg(self) -> Lanes {
        let a = self.0;
        Lanes([-a[0], -a[1], -a[2], -a[3]])
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn lanes_of(f: impl Fn(usize) -> f64) -> Lanes {
        Lanes([f(0), f(1), f(2), f(3)])
    }

    /// Each lane is the scalar operation on that lane, bit for bit.
    #[test]
    fn each_lane_is_the_scalar_operation() {
        // Opaque inputs: with constants the optimiser folds the scalar side
        // at compile time (its `powi` folding differs from the run-time
        // call in the last bit), and the test would compare the folding,
        // not what a run computes.
        let a = std::hint::black_box(lanes_of(|i| 0.37 + 1.3 * i as f64));
        let b = std::hint::black_box(lanes_of(|i| -2.1 + 0.77 * i as f64));
        let s = std::hint::black_box(1.618);
        // Each lane value against the same expression on one lane's f64s.
        type Scalar = fn(f64, f64, f64) -> f64;
        let checks: [(Lanes, Scalar); 10] = [
            (a + b, |x, y, _| x + y),
            (a - b, |x, y, _| x - y),
            (a * b, |x, y, _| x * y),
            (a / b, |x, y, _| x / y),
            (a * s - b / s, |x, y, s| x * s - y / s),
            (s - a, |x, _, s| s - x),
            (s / a + -b, |x, y, s| s / x + -y),
            (a.powi(3) * b.powi(-2), |x, y, _| x.powi(3) * y.powi(-2)),
            (a.sqrt().recip() + b.sin() * a.ln(), |x, y, _| {
                x.sqrt().recip() + y.sin() * x.ln()
            }),
            (a.powf(b) + a.powf(s), |x, y, s| x.powf(y) + x.powf(s)),
        ];
        for (k, (got, want)) in checks.iter().enumerate() {
            for i in 0..WIDTH {
                let w = want(a.0[i], b.0[i], s);
                assert_eq!(got.0[i].to_bits(), w.to_bits(), "check {k}, lane {i}");
            }
        }
        assert_eq!(lanes(2.5), Lanes::splat(2.5));
        assert_eq!(lanes(a), a);
    }
}
