//! A profiling target: the quasilinear field on the spherical pendulum.
#[path = "../tests/models/mod.rs"]
mod models;
use lagc_runtime::driver::{run, Options};
use lagc_runtime::method::Method;
use lagc_runtime::model::Model;
use lagc_runtime::tolerance::Tolerance;
use models::DoublePendulum as SphericalPendulum;
fn main() {
    let mut model = SphericalPendulum::new(&[10.0]);
    let x0 = model.initial_state(&[None; 4]).unwrap();
    let options = Options {
        method: Method::Field,
        tol: Tolerance {
            rtol: 1e-10,
            atol: 1e-10,
        },
        ..Options::default()
    };
    for _ in 0..200 {
        run(&mut model, &options, 0.0, 10.0, &x0, &[10.0], |_, _, _| {
            Ok(())
        })
        .unwrap();
    }
}
