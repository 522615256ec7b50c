//! Symbolic work that scales with depth (issue 29): `sin` nested `d` deep
//! around the velocity product `q1*q2'` (`scripts/gen_nested.py`). Before
//! the sealed products and the shared names, `lagc derive` printed 28 MB at
//! d = 120 (532 KB at d = 30) and the arena grew like d³. These bounds
//! catch a return of the blow-up without timing anything.

fn nested(depth: usize) -> String {
    let mut chain = String::from("q1*q2'");
    for _ in 0..depth {
        chain = format!("sin({chain})");
    }
    format!(
        "coord q1, q2;\nlagrangian = q1'^2 / 2 + q2'^2 / 2 + {chain};\n\
         initial q1 = 0.1, q2 = 0, q1' = 0.1, q2' = 0.1;\ntime 0 .. 1;\n"
    )
}

/// The text `lagc derive` prints (the derivation and the field's section)
/// and the number of nodes the arena built.
fn derive_text(depth: usize) -> (String, usize) {
    // On the big stack the commands run on: the walks recurse with depth.
    lagc::on_big_stack(|| derive_on_this_stack(depth))
}

fn derive_on_this_stack(depth: usize) -> (String, usize) {
    let model = lagc::frontend(&nested(depth)).expect("the nested model checks");
    let (derivation, _) = lagc::mechanics::derive_checked(&model).expect("it derives");
    let mut arena = derivation.arena.clone();
    let field = lagc::field::field_system(&mut arena, &derivation.reduced);
    let text = derivation.text() + &field.text(&arena, &derivation.reduced.state);
    (text, arena.len())
}

#[test]
fn a_30_deep_nesting_prints_through_shared_names() {
    let (text, nodes) = derive_text(30);
    eprintln!("d = 30: {} bytes, {nodes} nodes", text.len());
    assert!(text.contains("shared subexpressions"), "{}", &text[..400]);
    assert!(text.len() < 100_000, "{} bytes", text.len());
    assert!(nodes < 20_000, "{nodes} nodes");
}

#[test]
fn a_120_deep_nesting_stays_small_in_the_dag_and_in_print() {
    let (text, nodes) = derive_text(120);
    eprintln!("d = 120: {} bytes, {nodes} nodes", text.len());
    assert!(text.len() < 400_000, "{} bytes", text.len());
    assert!(nodes < 100_000, "{nodes} nodes");
}
