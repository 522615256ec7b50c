//! A snapshot per stage for every example (insta glob: a new example gets
//! its snapshots by being added): the AST (`ast`, `Debug` without spans), the IR the mechanics starts from (`ir`: the Lagrangian,
//! the constraints and the generalized forces, lowered), the coefficient
//! system of the field method (`coefficients`), the kernel (`kernel`) and
//! the generated `lib.rs` (`lib_rs`). Equations (4) and the reduced system
//! (7) are the `text` snapshots of `tests/it/mechanics/examples.rs`.

use lagc::emit::EmitOptions;
use lagc::ir::Symbol;

/// `{:#?}` without spans (a comment edited above the model would move
/// them all; the error files' headers pin positions), and every node with
/// one one-line field on one line: `Number(1.0)`, `Ident { name: "x" }`.
fn compact_debug(value: &impl std::fmt::Debug) -> String {
    let pretty = format!("{value:#?}");
    // A span is four lines: `span: Span {`, `start: …,`, `end: …,`, `},`.
    let mut lines: Vec<String> = Vec::new();
    let mut skip = 0;
    for line in pretty.lines() {
        let field = line.trim_start();
        if field.starts_with("span: Span {") || field.starts_with("func_span: Span {") {
            skip = 4;
        }
        if skip > 0 {
            skip -= 1;
            continue;
        }
        lines.push(line.to_string());
    }
    loop {
        let mut merged = false;
        let mut i = 0;
        while i + 2 < lines.len() {
            let (open, inner, close) = (&lines[i], lines[i + 1].trim(), lines[i + 2].trim());
            let pair = match open.chars().last() {
                Some('(') => Some(')'),
                Some('{') => Some('}'),
                Some('[') => Some(']'),
                _ => None,
            };
            if let Some(pair) = pair {
                let closes = close.strip_suffix(',').unwrap_or(close) == pair.to_string();
                let simple = !inner.ends_with(['(', '{', '[']);
                if closes && simple {
                    let inner = inner.strip_suffix(',').unwrap_or(inner);
                    let comma = if close.ends_with(',') { "," } else { "" };
                    let pad = if pair == '}' { " " } else { "" };
                    lines[i] = format!("{open}{pad}{inner}{pad}{pair}{comma}");
                    lines.drain(i + 1..i + 3);
                    merged = true;
                }
            }
            i += 1;
        }
        if !merged {
            break;
        }
    }
    lines.join("\n") + "\n"
}

fn ir_text(derivation: &lagc::mechanics::Derivation) -> String {
    let a = &derivation.arena;
    let name = |coord: u32, order: u32| a.symbol_name(Symbol::Jet { coord, order });
    let mut out = format!("L = {}\n", a.display(derivation.lagrangian));
    for &(d, phi) in &derivation.constraints {
        out.push_str(&format!(
            "constraint {} = {}\n",
            name(d, derivation.k),
            a.display(phi)
        ));
    }
    for (j, &f) in derivation.forces.iter().enumerate() {
        out.push_str(&format!(
            "R + Q on {} = {}\n",
            name(j as u32, 0),
            a.display(f)
        ));
    }
    out
}

#[test]
fn every_example_has_a_snapshot_per_stage() {
    insta::glob!("../../examples", "*.lag", |path| {
        let source = std::fs::read_to_string(path).unwrap();
        let name = path.file_stem().unwrap().to_string_lossy().into_owned();
        // Computed on the big stack; asserted here, where the glob's
        // settings (the snapshot's suffix) are bound.
        let [ast, ir, coefficients, kernel, lib_rs] = lagc::on_big_stack(|| {
            let ast = lagc::syntax::parse(&source).unwrap_or_else(|d| panic!("{name}: {d:?}"));
            let model = lagc::frontend(&source).unwrap_or_else(|d| panic!("{name}: {d:?}"));
            let (derivation, _) =
                lagc::mechanics::derive_checked(&model).unwrap_or_else(|d| panic!("{name}: {d:?}"));
            let ir = ir_text(&derivation);
            let reduced = derivation.reduced.clone();
            let mut arena = derivation.arena.clone();
            let field = lagc::field::field_system(&mut arena, &reduced);
            let coefficients = field.text(&arena, &reduced.state);
            let (kernel, _) = lagc::pipeline::kernel_of(&model, derivation)
                .unwrap_or_else(|d| panic!("{name}: {d:?}"));
            let options = EmitOptions {
                model_name: name.clone(),
                source_hash: "test".to_string(),
                runtime_path: "../../runtime".to_string(),
                package_key: None,
            };
            let (generated, _) = lagc::pipeline::generate_crate(&model, &options)
                .unwrap_or_else(|d| panic!("{name}: {d:?}"));
            let lib_rs = generated.file("src/lib.rs").unwrap().to_string();
            [
                compact_debug(&ast),
                ir,
                coefficients,
                kernel.to_string(),
                lib_rs,
            ]
        });
        insta::assert_snapshot!("ast", ast);
        insta::assert_snapshot!("ir", ir);
        insta::assert_snapshot!("coefficients", coefficients);
        insta::assert_snapshot!("kernel", kernel);
        insta::assert_snapshot!("lib_rs", lib_rs);
    });
}
