//! The eigenvalues of `A` (a real, generally non-symmetric matrix: a real
//! Schur form, nalgebra's), with each one's frequency and damping ratio.

use nalgebra::DMatrix;

/// `λ = re + i·im`.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Eigenvalue {
    pub re: f64,
    pub im: f64,
}

impl Eigenvalue {
    /// `|λ|`: the undamped natural frequency of a pair (rad per unit time).
    pub fn natural_frequency(self) -> f64 {
        self.re.hypot(self.im)
    }

    /// `|Im λ|`: the frequency the motion oscillates at.
    pub fn frequency(self) -> f64 {
        self.im.abs()
    }

    /// `ζ = −Re λ / |λ|` (1 critically damped, 0 undamped, < 0 growing);
    /// `None` for λ = 0.
    pub fn damping_ratio(self) -> Option<f64> {
        let w = self.natural_frequency();
        (w > 0.0).then(|| -self.re / w)
    }
}

/// The eigenvalues, largest real part first (pairs: positive imaginary
/// part first). Empty for an empty matrix; all NaN when the Schur
/// iteration does not converge.
pub fn eigenvalues(a: &[Vec<f64>]) -> Vec<Eigenvalue> {
    let n = a.len();
    if n == 0 {
        return Vec::new();
    }
    let m = DMatrix::from_fn(n, n, |r, c| a[r][c]);
    let Some(schur) = nalgebra::linalg::Schur::try_new(m, f64::EPSILON, 10_000) else {
        return vec![
            Eigenvalue {
                re: f64::NAN,
                im: f64::NAN
            };
            n
        ];
    };
    let mut out: Vec<Eigenvalue> = schur
        .complex_eigenvalues()
        .iter()
        .map(|c| Eigenvalue { re: c.re, im: c.im })
        .collect();
    out.sort_by(|x, y| y.re.total_cmp(&x.re).then_with(|| y.im.total_cmp(&x.im)));
    out
}
