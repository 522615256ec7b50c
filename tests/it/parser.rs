//! Parser unit tests: precedence, associativity, primes, spans.

use lagc::syntax::ast::{BinOp, Expr, ExprKind, ItemKind};
use lagc::syntax::parse;

/// The parsed param value, as a fully parenthesised string.
fn shape(expr_source: &str) -> String {
    let model = parse(&format!("param x = {expr_source};")).expect("parses");
    match &model.items[0].kind {
        ItemKind::Param { value, .. } => show(value),
        other => panic!("not a param: {other:?}"),
    }
}

fn show(expr: &Expr) -> String {
    match &expr.kind {
        ExprKind::Number(n) => format!("{n}"),
        ExprKind::Var { name, primes } => format!("{}{}", name.name, "'".repeat(*primes as usize)),
        ExprKind::Neg(inner) => format!("(-{})", show(inner)),
        ExprKind::Binary { op, lhs, rhs } => {
            let op = match op {
                BinOp::Add => "+",
                BinOp::Sub => "-",
                BinOp::Mul => "*",
                BinOp::Div => "/",
                BinOp::Pow => "^",
            };
            format!("({} {op} {})", show(lhs), show(rhs))
        }
        ExprKind::Call { func, args, .. } => {
            let args: Vec<String> = args.iter().map(show).collect();
            format!("{}({})", func.name(), args.join(", "))
        }
        ExprKind::Vector(elements) => {
            let elements: Vec<String> = elements.iter().map(show).collect();
            format!("({})", elements.join(", "))
        }
        ExprKind::Component { base, axis } => format!("{}.{}", show(base), axis.name),
        ExprKind::Compare { op, lhs, rhs } => {
            format!("({} {} {})", show(lhs), op.symbol(), show(rhs))
        }
        ExprKind::Logic { op, lhs, rhs } => format!("({} {op:?} {})", show(lhs), show(rhs)),
        ExprKind::Not(inner) => format!("(not {})", show(inner)),
        ExprKind::If {
            cond,
            then,
            otherwise,
        } => format!(
            "(if {} then {} else {})",
            show(cond),
            show(then),
            show(otherwise)
        ),
    }
}

#[test]
fn power_binds_tighter_than_minus() {
    assert_eq!(shape("-x^2"), "(-(x ^ 2))");
    assert_eq!(shape("--x"), "(-(-x))");
}

#[test]
fn power_is_right_associative() {
    assert_eq!(shape("a^b^c"), "(a ^ (b ^ c))");
    assert_eq!(shape("a^-b^c"), "(a ^ (-(b ^ c)))");
}

#[test]
fn other_operators_are_left_associative() {
    assert_eq!(shape("a-b-c"), "((a - b) - c)");
    assert_eq!(shape("a/b/c"), "((a / b) / c)");
    assert_eq!(shape("a+b*c^2"), "(a + (b * (c ^ 2)))");
    assert_eq!(shape("(a+b)*c"), "((a + b) * c)");
    assert_eq!(shape("a * -b"), "(a * (-b))");
}

#[test]
fn primes_and_numbers() {
    assert_eq!(shape("q1''' + q1'"), "(q1''' + q1')");
    assert_eq!(
        shape("2 + 0.5 + 1e-3 + 2E3"),
        "(((2 + 0.5) + 0.001) + 2000)"
    );
    assert_eq!(shape("exp(-alpha * t)"), "exp(((-alpha) * t))");
}

#[test]
fn spans_cover_source_text() {
    let source = "param x = (a + b) * sin(c);";
    let model = parse(source).unwrap();
    let ItemKind::Param { name, value } = &model.items[0].kind else {
        panic!()
    };
    assert_eq!(&source[name.span.range()], "x");
    assert_eq!(&source[value.span.range()], "(a + b) * sin(c)");
    assert_eq!(&source[model.items[0].span.range()], source);
    let ExprKind::Binary { lhs, rhs, .. } = &value.kind else {
        panic!()
    };
    assert_eq!(&source[lhs.span.range()], "(a + b)");
    let ExprKind::Call { func_span, .. } = &rhs.kind else {
        panic!()
    };
    assert_eq!(&source[func_span.range()], "sin");
}

#[test]
fn comments_and_empty_files() {
    assert!(parse("").unwrap().items.is_empty());
    assert!(parse("// only a comment").unwrap().items.is_empty());
    assert_eq!(
        parse("coord q; // trailing\ntime 0 .. 1;")
            .unwrap()
            .items
            .len(),
        2
    );
}

#[test]
fn long_chains_are_rejected_not_overflowed() {
    let chain = vec!["1"; 100_000].join("+");
    let errors = lagc::on_big_stack(|| parse(&format!("param x = {chain};"))).unwrap_err();
    assert_eq!(errors[0].code, lagc::diagnostic::codes::NESTING_TOO_DEEP);
    // Just under the limit parses, on an ordinary test thread's stack too.
    let chain = vec!["1"; lagc::syntax::MAX_EXPR_DEPTH].join("^");
    assert!(parse(&format!("param x = {chain};")).is_ok());
}

#[test]
fn a_long_flat_chain_is_one_level_of_nesting() {
    // The potential of a 50-link pendulum: 1,275 terms in one sum.
    let terms: Vec<String> = (1..=50)
        .flat_map(|i| (1..=i).map(|j| format!("cos(q{j})")))
        .collect();
    assert_eq!(terms.len(), 1275);
    let source = format!("param V = 0;\nlagrangian = {};\n", terms.join(" + "));
    // Like the CLI, on the front end's stack: the tree of a chain is as high
    // as the chain is long.
    assert!(lagc::on_big_stack(|| parse(&source).is_ok()));
    // A chain longer than the tree-height limit is refused, not recursed.
    let long = format!("lagrangian = {};", vec!["x'"; 25_000].join(" + "));
    let message = lagc::on_big_stack(|| parse(&long).unwrap_err()[0].message.clone());
    let limit = lagc::syntax::MAX_TREE_HEIGHT;
    assert!(
        message.contains(&format!("more than {limit} terms in a chain")),
        "{message:?}"
    );
}
