//! The mechanics on the planar N-link pendulum (`benches/data/pendulum_N.lag`,
//! written by `scripts/gen_pendulum.py`): parse + check + derive + reduce
//! time (minimum of several runs after a warm-up), and the size of the
//! reduced right side. Not a timed test: `cargo bench --bench derive`.

use lagc::mechanics::{derive, Highest};
use std::time::{Duration, Instant};

const SIZES: [u32; 4] = [3, 5, 8, 12];
const WARM_UP: usize = 2;
const RUNS: usize = 10;

fn main() {
    let root = env!("CARGO_MANIFEST_DIR");
    println!("N   parse+check+derive+reduce   DAG nodes   ops after sharing");
    for n in SIZES {
        let path = format!("{root}/benches/data/pendulum_{n}.lag");
        let source = match std::fs::read_to_string(&path) {
            Ok(s) => s,
            Err(e) => {
                eprintln!("{path}: {e} (run scripts/gen_pendulum.py)");
                continue;
            }
        };
        let run = || {
            let model = lagc::frontend(&source).expect("the pendulum checks");
            derive(&model).expect("the pendulum derives")
        };
        for _ in 0..WARM_UP {
            run();
        }
        let mut best = Duration::MAX;
        let mut derivation = None;
        for _ in 0..RUNS {
            let start = Instant::now();
            let d = run();
            best = best.min(start.elapsed());
            derivation = Some(d);
        }
        let Some(d) = derivation else { continue };
        let roots: Vec<_> = match &d.reduced.highest {
            Highest::Explicit(x) => x.clone(),
            Highest::Implicit {
                residual, jacobian, ..
            } => residual
                .iter()
                .chain(jacobian.iter().flatten())
                .copied()
                .collect(),
        };
        println!(
            "{n:<3} {:>10.2} ms {:>26} {:>19}",
            best.as_secs_f64() * 1e3,
            d.arena.dag_size(&roots),
            d.arena.op_count(&roots)
        );
    }
}
