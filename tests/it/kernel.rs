//! The kernel IR as text (stage 6): what the generated crate evaluates,
//! with the true time partials (mass laws move with `t`). One model with
//! a mass law and a reactive force, one with a constraint.

fn kernel_text(path: &str) -> String {
    let name = path;
    let source = std::fs::read_to_string(crate::root().join(path)).unwrap();
    let model = lagc::frontend(&source).unwrap_or_else(|d| panic!("{name}: {d:?}"));
    let mut derivation = lagc::mechanics::derive(&model).unwrap();
    let reduced = derivation.reduced.clone();
    let field = lagc::field::field_system(&mut derivation.arena, &reduced);
    let kernel = lagc::kernel::build(&model, &derivation, &field).unwrap();
    kernel.to_string()
}

/// `X = −sin(x)/M` keeps the mass law's value `M`, so `∂X/∂t` must hold
/// `∂X/∂M · M ρ` with `ρ = Ṁ/M` (issue 10's bug: it held nothing).
#[test]
fn kernel_time_partial_carries_the_mass_rate() {
    insta::assert_snapshot!(kernel_text("tests/data/mass_law_forms/pendulum_mass.lag"));
}

#[test]
fn kernel_of_the_vertical_rocket() {
    insta::assert_snapshot!(kernel_text("examples/vertical_rocket.lag"));
}

#[test]
fn kernel_of_the_knife_edge() {
    insta::assert_snapshot!(kernel_text("examples/knife_edge.lag"));
}

/// A mass law of the state (SPEC §2.3) reaches `X` as its expression of
/// `x`, so the exact `∂X/∂x` and `∂X/∂t` see the mass move with the state
/// and with `t` (a law of `t` alone that stays a symbol moves with its
/// rate): both agree with central differences of `X`, and no expression
/// the crate evaluates holds the state law's symbol.
#[test]
fn kernel_partials_follow_a_mass_law_of_the_state() {
    use lagc::ir::Symbol;
    use lagc::kernel::Motion;
    let source =
        std::fs::read_to_string(crate::root().join("tests/data/mass_of_state_kernel.lag")).unwrap();
    let model = lagc::frontend(&source).unwrap();
    let mut derivation = lagc::mechanics::derive(&model).unwrap();
    assert_eq!(derivation.state_laws.len(), 1);
    let reduced = derivation.reduced.clone();
    let field = lagc::field::field_system(&mut derivation.arena, &reduced);
    let kernel = lagc::kernel::build(&model, &derivation, &field).unwrap();
    assert_eq!(kernel.state_laws, vec![0]);
    let Motion::Explicit(motion) = &kernel.motion else {
        panic!("an explicit system")
    };
    let a = &kernel.arena;
    let roots: Vec<_> = motion
        .rhs
        .iter()
        .copied()
        .chain(motion.jacobian.iter().map(|&(_, _, d)| d))
        .chain(motion.time_partial.iter().map(|&(_, d)| d))
        .collect();
    for &r in &roots {
        assert!(
            !a.free_symbols(r).contains(&Symbol::Mass(0)),
            "{}",
            a.display(r)
        );
    }
    assert!(kernel.remaining_masses.contains(&1), "C stays a symbol");
    let params = derivation.param_defaults.clone();
    // X at (t, x): params at their defaults, each mass symbol at its law.
    let x_at = |t: f64, x: &[f64]| -> f64 {
        fn env(kernel: &lagc::kernel::Kernel, params: &[f64], t: f64, x: &[f64], s: Symbol) -> f64 {
            match s {
                Symbol::Time => t,
                Symbol::Param(i) => params[i as usize],
                Symbol::Mass(i) => kernel.arena.eval(kernel.masses[i as usize].1, &|s| {
                    env(kernel, params, t, x, s)
                }),
                s => x[kernel.state.iter().position(|&q| q == s).unwrap()],
            }
        }
        a.eval(motion.rhs[0], &|s| env(&kernel, &params, t, x, s))
    };
    let partial = |e, t: f64, x: &[f64]| {
        a.eval(e, &|s| match s {
            Symbol::Time => t,
            Symbol::Param(i) => params[i as usize],
            Symbol::Mass(i) => a.eval(kernel.masses[i as usize].1, &|s| match s {
                Symbol::Time => t,
                Symbol::Param(i) => params[i as usize],
                _ => f64::NAN,
            }),
            s => x[kernel.state.iter().position(|&q| q == s).unwrap()],
        })
    };
    let row = kernel.highest_row(0);
    let h = 1e-6;
    for &(t, x0, v0) in &[(0.3, 1.2, -0.7), (0.9, 0.4, 1.5), (1.7, 2.5, 0.2)] {
        let x = [x0, v0];
        for column in 0..2 {
            let mut up = x;
            let mut down = x;
            up[column] += h;
            down[column] -= h;
            let difference = (x_at(t, &up) - x_at(t, &down)) / (2.0 * h);
            let exact = motion
                .jacobian
                .iter()
                .find(|&&(r, c, _)| r == row && c == column)
                .map_or(0.0, |&(_, _, d)| partial(d, t, &x));
            assert!(
                (exact - difference).abs() <= 1e-7 * exact.abs().max(1.0),
                "∂X/∂x[{column}] at t = {t}: {exact} vs {difference}"
            );
        }
        let difference = (x_at(t + h, &x) - x_at(t - h, &x)) / (2.0 * h);
        let exact = motion
            .time_partial
            .iter()
            .find(|&&(r, _)| r == row)
            .map_or(0.0, |&(_, d)| partial(d, t, &x));
        assert!(
            (exact - difference).abs() <= 1e-7 * exact.abs().max(1.0),
            "∂X/∂t at t = {t}: {exact} vs {difference}"
        );
    }
}

/// Latching a kernel's selections (`kernel/switches.rs`) rebuilds only the
/// nodes that hold a selection: a node without one is taken as it stands,
/// which is what rebuilding it from its own children through the
/// constructors gives. Checked here on every node of every example's
/// kernel that holds no selection.
#[test]
fn a_node_without_a_selection_is_its_own_canonical_form() {
    use lagc::ir::Node;
    use lagc::kernel::Motion;
    let mut nodes = 0;
    for path in crate::expect::lag_files("examples") {
        let name = path.display().to_string();
        let source = std::fs::read_to_string(&path).unwrap();
        let model = lagc::frontend(&source).unwrap_or_else(|d| panic!("{name}: {d:?}"));
        let (derivation, _) = lagc::mechanics::derive_checked(&model).unwrap();
        let (kernel, _) = lagc::pipeline::kernel_of(&model, derivation).unwrap();
        let mut arena = kernel.arena.clone();
        // The right side and its exact Jacobian, as the crate evaluates them.
        let mut roots = kernel.rhs_roots();
        match &kernel.motion {
            Motion::Explicit(m) => {
                roots.extend(m.jacobian.iter().map(|&(_, _, e)| e));
                roots.extend(m.time_partial.iter().map(|&(_, e)| e));
            }
            Motion::Implicit(m) => {
                roots.extend(m.g_x.iter().map(|&(_, _, e)| e));
                roots.extend(m.g_t.iter().map(|&(_, e)| e));
            }
        }
        for e in arena.reachable(&roots) {
            if arena.has_select(e) {
                continue;
            }
            let rebuilt = match arena.node(e).clone() {
                Node::Const(_) | Node::Sym(_) => e,
                Node::Add(ts) => arena.add(&ts),
                Node::Mul(fs) => arena.mul(&fs),
                Node::Pow(b, x) => arena.pow(b, x),
                Node::Func(f, u) => arena.func(f, u),
                Node::Select(..) => unreachable!("{name}: a selection holds itself"),
            };
            assert_eq!(rebuilt, e, "{name}: {}", arena.display(e));
            nodes += 1;
        }
    }
    assert!(nodes > 2_000, "{nodes} nodes checked");
}
