//! The N-link planar pendulum: the size that must stay fast (SPEC: < 50 ms
//! end to end for N = 12). This test checks the equations; the time and the
//! DAG size are printed for a by-hand measurement:
//! `cargo test --release --test it ir::pendulum -- --nocapture`.

use super::{env_at, Rng};
use lagc::ir::{Arena, ExprId, Func, Names, Symbol};
use std::time::Instant;

const N: u32 = 12;
const G: Symbol = Symbol::Param(0);

/// `L = Σ_k ½(ẋ_k² + ẏ_k²) + g Σ_k Σ_{i≤k} cos θ_i` with unit masses and
/// links, built as lowering a hand-written Lagrangian would build it.
fn lagrangian(a: &mut Arena) -> ExprId {
    let half = a.constant(0.5);
    let g = a.symbol(G);
    let mut energy = Vec::new();
    let (mut vx, mut vy, mut height) = (Vec::new(), Vec::new(), Vec::new());
    for i in 0..N {
        let (th, thd) = (a.jet(i, 0), a.jet(i, 1));
        let (c, s) = (a.func(Func::Cos, th), a.func(Func::Sin, th));
        vx.push(a.mul(&[c, thd]));
        vy.push(a.mul(&[s, thd]));
        height.push(c);
        let (sx, sy) = (a.add(&vx), a.add(&vy));
        let (sx2, sy2) = (a.powi(sx, 2), a.powi(sy, 2));
        let v2 = a.add(&[sx2, sy2]);
        energy.push(a.mul(&[half, v2]));
        let h = a.add(&height);
        energy.push(a.mul(&[g, h]));
    }
    a.add(&energy)
}

/// The Euler–Lagrange expressions `E_i = D(∂L/∂θ_i') − ∂L/∂θ_i` and the
/// mass matrix `∂E_i/∂θ_j''`.
fn equations(a: &mut Arena, l: ExprId) -> (Vec<ExprId>, Vec<Vec<ExprId>>) {
    let e: Vec<ExprId> = (0..N)
        .map(|i| {
            let p = a.diff(l, Symbol::Jet { coord: i, order: 1 });
            let dp = a.total_derivative(p);
            let f = a.diff(l, Symbol::Jet { coord: i, order: 0 });
            a.sub(dp, f)
        })
        .collect();
    let m = e
        .iter()
        .map(|&ei| {
            (0..N)
                .map(|j| a.diff(ei, Symbol::Jet { coord: j, order: 2 }))
                .collect()
        })
        .collect();
    (e, m)
}

/// Equation (4) with k = 1, the route of the mechanics:
/// `2 ∂(D²L)/∂θ_i'' − 3 ∂(DL)/∂θ_i'`.
fn equation_four(a: &mut Arena, l: ExprId) -> Vec<ExprId> {
    let l1 = a.total_derivative(l);
    let l2 = a.total_derivative(l1);
    let (two, minus_three) = (a.constant(2.0), a.constant(-3.0));
    (0..N)
        .map(|i| {
            let p2 = a.diff(l2, Symbol::Jet { coord: i, order: 2 });
            let p1 = a.diff(l1, Symbol::Jet { coord: i, order: 1 });
            let left = a.mul(&[two, p2]);
            let right = a.mul(&[minus_three, p1]);
            a.add(&[left, right])
        })
        .collect()
}

#[test]
fn twelve_link_pendulum() {
    let start = Instant::now();
    let mut a = Arena::new(Names {
        params: vec!["g".into()],
        coords: (1..=N).map(|i| format!("th{i}")).collect(),
        masses: Vec::new(),
        inputs: Vec::new(),
    });
    let l = lagrangian(&mut a);
    let (e, m) = equations(&mut a, l);
    let elapsed = start.elapsed();
    let four = equation_four(&mut a, l);
    let elapsed_four = start.elapsed() - elapsed;
    let roots: Vec<ExprId> = e.iter().chain(m.iter().flatten()).copied().collect();
    eprintln!(
        "N = {N}: L, E_i and the mass matrix in {:.2} ms; {} nodes in the arena, \
         {} reachable, {} operations",
        elapsed.as_secs_f64() * 1e3,
        a.len(),
        a.dag_size(&roots),
        a.op_count(&roots)
    );
    eprintln!(
        "N = {N}: equation (4) through D²L in a further {:.2} ms; {} nodes in the arena",
        elapsed_four.as_secs_f64() * 1e3,
        a.len()
    );

    // E_i = Σ_j c_ij [cos(θi−θj) θj'' + sin(θi−θj) θj'²] + g c_i sin θi,
    // c_ij = N − max(i, j), c_i = N − i (0-based).
    let mut rng = Rng::new(3);
    for p in 0..3 {
        let base = env_at(p);
        let angles: Vec<f64> = (0..N).map(|_| rng.range(-3.0, 3.0)).collect();
        let env = |s: Symbol| match s {
            Symbol::Jet { coord, order: 0 } => angles[coord as usize],
            other => base(other),
        };
        let g = env(G);
        for i in 0..N as usize {
            let mut expected = g * (N as usize - i) as f64 * angles[i].sin();
            for j in 0..N as usize {
                let c = (N as usize - i.max(j)) as f64;
                let d = angles[i] - angles[j];
                let jet = |order| {
                    env(Symbol::Jet {
                        coord: j as u32,
                        order,
                    })
                };
                let mass = a.eval(m[i][j], &env);
                assert!((mass - c * d.cos()).abs() < 1e-12 * N as f64, "A[{i}][{j}]");
                expected += c * (d.cos() * jet(2) + d.sin() * jet(1).powi(2));
            }
            let got = a.eval(e[i], &env);
            assert!(
                (got - expected).abs() < 1e-10 * (1.0 + expected.abs()),
                "E[{i}]"
            );
            let got = a.eval(four[i], &env);
            assert!(
                (got - expected).abs() < 1e-10 * (1.0 + expected.abs()),
                "(4)[{i}]"
            );
        }
    }
}
