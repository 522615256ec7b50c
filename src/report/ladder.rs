//! The tolerances `lagc report` runs at, and its references.

use super::Method;

/// `rtol = 1e-3, 1e-4, …, 1e-12`: from "plot accuracy" to near the limit
/// of double precision for an order-8 method.
pub fn default_tolerances() -> Vec<f64> {
    (3..=12).map(|k| 10f64.powi(-k)).collect()
}

/// `atol = rtol · 1e-2`: the absolute part only matters for components
/// passing near zero, where it keeps the relative test from asking for
/// digits that are not there; two decades below keeps it from deciding
/// the step for components of size ≳ 0.01.
pub fn atol_for(rtol: f64) -> f64 {
    rtol * 1e-2
}

/// The tolerance of the reference runs when the model states no exact
/// solution (its `atol` by [`atol_for`]).
pub const REFERENCE_RTOL: f64 = 1e-13;

/// The method whose run at [`REFERENCE_RTOL`] is the reference for
/// `method`: never the method itself, so that a method's systematic error
/// cannot cancel against itself.
pub fn reference_for(method: Method) -> Method {
    match method {
        Method::Field | Method::Stiff => Method::Explicit,
        Method::Explicit => Method::Field,
    }
}

/// `"1e-4,1e-8"` → `[1e-4, 1e-8]`; every value finite and in `(0, 1)`.
pub fn parse_tolerances(text: &str) -> Result<Vec<f64>, String> {
    let mut tolerances = Vec::new();
    for part in text.split(',').map(str::trim) {
        match part.parse::<f64>() {
            Ok(v) if v > 0.0 && v < 1.0 => tolerances.push(v),
            _ => return Err(format!("`{part}` is not a tolerance in (0, 1)")),
        }
    }
    if tolerances.is_empty() {
        return Err("no tolerances".to_string());
    }
    Ok(tolerances)
}
