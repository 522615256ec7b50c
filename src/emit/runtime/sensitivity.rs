//! The coefficient system augmented by its sensitivities to the anchor,
//! `S = ∂f/∂c` with `S' = (∂F/∂f) S`, as one first-order system
//! `y = (f, S)` (S stored column by column: column `j` is `∂f/∂c_j`).

use super::error::Failure;
use super::system::{CoefficientSystem, Motion};
use nalgebra::{DMatrix, DVectorView};
use std::cell::RefCell;

pub struct Sensitized<'a, C: CoefficientSystem + ?Sized> {
    pub coefficients: &'a C,
    /// `∂F/∂f`, reused by every right-side evaluation: `rhs` takes `&self`
    /// (the integrators see a [`Motion`]) and is called a dozen times per
    /// step, so a fresh `N × N` allocation each time showed in the profile.
    jacobian_scratch: RefCell<DMatrix<f64>>,
}

impl<'a, C: CoefficientSystem + ?Sized> Sensitized<'a, C> {
    pub fn new(coefficients: &'a C) -> Self {
        let n = coefficients.dim();
        Sensitized {
            coefficients,
            jacobian_scratch: RefCell::new(DMatrix::zeros(n, n)),
        }
    }

    /// The augmented state at an anchor `c`: `f = c`, `S = I`.
    pub fn anchored_state(c: &[f64]) -> Vec<f64> {
        let n = c.len();
        let mut y = vec![0.0; n + n * n];
        y[..n].copy_from_slice(c);
        for i in 0..n {
            y[n + i * n + i] = 1.0;
        }
        y
    }

    /// `S` as a matrix view into the augmented state.
    pub fn sensitivities(y: &[f64], n: usize) -> nalgebra::DMatrixView<'_, f64> {
        nalgebra::DMatrixView::from_slice(&y[n..n + n * n], n, n)
    }
}

impl<C: CoefficientSystem + ?Sized> Motion for Sensitized<'_, C> {
    fn dim(&self) -> usize {
        let n = self.coefficients.dim();
        n + n * n
    }

    fn rhs(&self, t: f64, y: &[f64], dy: &mut [f64]) -> Result<(), Failure> {
        let n = self.coefficients.dim();
        let (f, s) = y.split_at(n);
        let (df, ds) = dy.split_at_mut(n);
        self.coefficients.rhs(t, f, df)?;
        let mut jacobian = self.jacobian_scratch.borrow_mut();
        // The trait promises a zeroed matrix: only non-zeros are written.
        jacobian.fill(0.0);
        self.coefficients.jacobian(t, f, &mut jacobian)?;
        let s = nalgebra::DMatrixView::from_slice(s, n, n);
        let mut ds = nalgebra::DMatrixViewMut::from_slice(ds, n, n);
        ds.gemm(1.0, &*jacobian, &s, 0.0);
        Ok(())
    }

    /// Exact only for a linear coefficient system, where `∂(JS)/∂f = 0`;
    /// the field method uses the stiff integrator only then.
    fn jacobian(&self, t: f64, y: &[f64], jac: &mut DMatrix<f64>) -> Result<(), Failure> {
        let n = self.coefficients.dim();
        let mut block = DMatrix::zeros(n, n);
        self.coefficients.jacobian(t, &y[..n], &mut block)?;
        for k in 0..=n {
            jac.view_mut((k * n, k * n), (n, n)).copy_from(&block);
        }
        Ok(())
    }

    /// For a linear `F = G(t) f + g(t)`: `∂F/∂t = G' f + g'`, and
    /// `∂(G S_j)/∂t = G' S_j = F_t(t, S_j) − F_t(t, 0)`.
    fn time_partial(&self, t: f64, y: &[f64], dydt: &mut [f64]) -> Result<(), Failure> {
        let n = self.coefficients.dim();
        self.coefficients.time_partial(t, &y[..n], &mut dydt[..n])?;
        let mut free = vec![0.0; n];
        self.coefficients
            .time_partial(t, &vec![0.0; n], &mut free)?;
        let mut column = vec![0.0; n];
        for j in 0..n {
            let s_j = DVectorView::from_slice(&y[n + j * n..n + (j + 1) * n], n);
            column.iter_mut().for_each(|v| *v = 0.0);
            self.coefficients
                .time_partial(t, s_j.as_slice(), &mut column)?;
            for i in 0..n {
                dydt[n + j * n + i] = column[i] - free[i];
            }
        }
        Ok(())
    }

    fn component_name(&self, i: usize) -> String {
        let n = self.coefficients.dim();
        if i < n {
            format!("f_{}", i + 1)
        } else {
            let k = i - n;
            format!("S_{}_{}", k % n + 1, k / n + 1)
        }
    }
}
