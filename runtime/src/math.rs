//! Elementary functions the generated code calls besides `f64`'s methods.

/// `(sin x, cos x)` in one call. With glibc it is `sincos`, what a C
/// compiler emits for a sine and a cosine of one argument (it shares the
/// argument reduction; glibc computes both with the routines of `sin` and
/// `cos`, so the values are theirs); elsewhere the two calls.
#[inline]
pub fn sin_cos<T: SinCos>(x: T) -> (T, T) {
    x.sin_cos_of()
}

/// A value [`sin_cos`] takes: an `f64`, or four lanes of them (each lane
/// the `f64`'s call: the same values).
pub trait SinCos: Sized {
    fn sin_cos_of(self) -> (Self, Self);
}

impl SinCos for f64 {
    #[inline]
    fn sin_cos_of(self) -> (f64, f64) {
        scalar_sin_cos(self)
    }
}

impl SinCos for crate::lanes::Lanes {
    #[inline]
    fn sin_cos_of(self) -> (Self, Self) {
        let (mut s, mut c) = ([0.0; 4], [0.0; 4]);
        for (i, &v) in self.0.iter().enumerate() {
            (s[i], c[i]) = scalar_sin_cos(v);
        }
        (crate::lanes::Lanes(s), crate::lanes::Lanes(c))
    }
}

#[inline]
fn scalar_sin_cos(x: f64) -> (f64, f64) {
    #[cfg(all(target_os = "linux", target_env = "gnu"))]
    {
        extern "C" {
            fn sincos(x: f64, sin: *mut f64, cos: *mut f64);
        }
        let (mut s, mut c) = (0.0, 0.0);
        // SAFETY: glibc's `sincos` (in libm, which std links on this
        // target) writes one f64 through each pointer and keeps neither.
        unsafe { sincos(x, &mut s, &mut c) };
        (s, c)
    }
    #[cfg(not(all(target_os = "linux", target_env = "gnu")))]
    {
        (x.sin(), x.cos())
    }
}

/// Gauss–Legendre's four nodes and weights on `[0, 1]` (exact for
/// polynomials of degree 7), each correctly rounded: the output checks'
/// quadratures of the right side along an extension (the field's pieces,
/// direct DOP853's steps).
pub const GAUSS_LEGENDRE_4: [(f64, f64); 4] = [
    (0.069_431_844_202_973_71, 0.173_927_422_568_726_93),
    (0.330_009_478_207_571_87, 0.326_072_577_431_273_07),
    (0.669_990_521_792_428_1, 0.326_072_577_431_273_07),
    (0.930_568_155_797_026_3, 0.173_927_422_568_726_93),
];

#[cfg(test)]
mod tests {
    #[test]
    fn sin_cos_is_sin_and_cos() {
        for i in -2000..2000 {
            let x = f64::from(i) * 0.0137 + 1e-3 * f64::from(i % 7);
            assert_eq!(super::sin_cos(x), (x.sin(), x.cos()), "at {x}");
        }
        for x in [0.0, -0.0, 1e300, -1e-300, f64::INFINITY, f64::NAN] {
            let (s, c) = super::sin_cos(x);
            assert_eq!(s.to_bits(), x.sin().to_bits());
            assert_eq!(c.to_bits(), x.cos().to_bits());
        }
    }
}
