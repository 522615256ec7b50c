//! No input makes the front end or the derivation panic or overflow its stack.
//!
//! A deterministic mutation test: 12,000 inputs per run, made by mutating
//! the examples and error files (byte flips, deletions, token insertions,
//! deletions, duplications and swaps) and by generators (random
//! expressions, deep nesting, long operator chains, huge numbers, random
//! bytes). The project's one PRNG with a fixed seed keeps runs reproducible
//! without a dependency; a failure prints the input that caused it.

use lagc::diagnostic;
use std::panic::{catch_unwind, AssertUnwindSafe};

const INPUTS: usize = 12_000;
const SEED: u64 = 0x1a9c_2003_f00d;

/// The project's one PRNG, with the choices the mutations need.
struct Rng(lagc::mechanics::Rng);

impl Rng {
    fn seeded(seed: u64) -> Rng {
        Rng(lagc::mechanics::Rng::new(seed))
    }

    fn next(&mut self) -> u64 {
        self.0.next_u64()
    }

    fn below(&mut self, n: usize) -> usize {
        self.0.below(n)
    }

    fn word(&mut self, words: &[&'static str]) -> &'static str {
        words[self.below(words.len())]
    }

    fn pick<'a, T>(&mut self, items: &'a [T]) -> &'a T {
        &items[self.below(items.len())]
    }
}

const TOKENS: &[&str] = &[
    "(",
    ")",
    "'",
    "''''",
    "^",
    "-",
    "+",
    "*",
    "/",
    ";",
    "=",
    ",",
    "..",
    "{",
    "}",
    " ",
    "\n",
    "//",
    "q1",
    "q2",
    "t",
    "M",
    "alpha",
    "P",
    "param",
    "coord",
    "mass",
    "lagrangian",
    "constraint",
    "point",
    "force",
    "initial",
    "time",
    "exact",
    "position",
    "absolute",
    "relative",
    "velocity",
    "sin(",
    "ln(",
    "sqrt(",
    "0",
    "1",
    "0.5",
    "1e-3",
    "1e999",
    "1e-999",
    "1e",
    "\u{0}",
    "é",
    "\u{feff}",
    "\t",
    "\r",
    "_",
    "9999999999999999999999",
    // Language v2 (SPEC §2.2).
    "let",
    "output",
    "stop",
    "when",
    "for",
    "if",
    "then",
    "else",
    "and",
    "or",
    "not",
    "<",
    ">=",
    ".x",
    ".z",
    "pi",
    "dot(",
    "cross(",
    "norm(",
    "abs(",
    "atan2(",
    "min(",
];

fn corpus() -> Vec<Vec<u8>> {
    let root = crate::root();
    let mut files = Vec::new();
    for dir in ["examples", "tests/data/errors"] {
        let Ok(entries) = std::fs::read_dir(root.join(dir)) else {
            continue;
        };
        let mut paths: Vec<_> = entries.filter_map(|e| e.ok().map(|e| e.path())).collect();
        paths.sort();
        for path in paths {
            if path.extension().is_some_and(|e| e == "lag") {
                files.push(std::fs::read(path).expect("corpus file is readable"));
            }
        }
    }
    assert!(!files.is_empty());
    files
}

fn mutate(rng: &mut Rng, mut bytes: Vec<u8>) -> Vec<u8> {
    for _ in 0..1 + rng.below(3) {
        let at = rng.below(bytes.len() + 1);
        match rng.below(6) {
            0 if !bytes.is_empty() => {
                let last = bytes.len() - 1;
                bytes[at.min(last)] = rng.next() as u8;
            }
            1 => {
                let end = (at + rng.below(8)).min(bytes.len());
                bytes.drain(at..end);
            }
            2 => {
                let token = rng.word(TOKENS).as_bytes();
                bytes.splice(at..at, token.iter().copied());
            }
            _ => bytes = mutate_tokens(rng, &bytes),
        }
    }
    bytes
}

/// Deletes, duplicates or swaps whitespace-separated tokens.
fn mutate_tokens(rng: &mut Rng, bytes: &[u8]) -> Vec<u8> {
    let text = String::from_utf8_lossy(bytes);
    let mut tokens: Vec<&str> = text.split_whitespace().collect();
    if tokens.is_empty() {
        return bytes.to_vec();
    }
    let (i, j) = (rng.below(tokens.len()), rng.below(tokens.len()));
    match rng.below(3) {
        0 => {
            tokens.remove(i);
        }
        1 => tokens.insert(i, tokens[j]),
        _ => tokens.swap(i, j),
    }
    tokens
        .join(if rng.below(2) == 0 { " " } else { "\n" })
        .into_bytes()
}

fn random_expr(rng: &mut Rng, depth: usize, out: &mut String) {
    if depth == 0 || rng.below(4) == 0 {
        out.push_str(rng.word(&[
            "q1", "q2'", "q1''", "t", "alpha", "M", "2", "0.5", "1e300", "P", "zz",
        ]));
        return;
    }
    match rng.below(4) {
        0 => {
            out.push_str(rng.word(&["-", "sin(", "exp(", "(", "foo("]));
            let close = !out.ends_with('-');
            random_expr(rng, depth - 1, out);
            if close {
                out.push(')');
            }
        }
        _ => {
            random_expr(rng, depth - 1, out);
            out.push_str(rng.word(&[" + ", " - ", " * ", " / ", "^"]));
            random_expr(rng, depth - 1, out);
        }
    }
}

fn generated(rng: &mut Rng) -> Vec<u8> {
    let text = match rng.below(7) {
        0 => {
            let mut e = [String::new(), String::new(), String::new()];
            for expr in &mut e {
                random_expr(rng, 6, expr);
            }
            format!(
                "param alpha = 1;\ncoord q1, q2;\nmass M = exp(-alpha*t);\nlagrangian = {};\n\
                 constraint q2' = {};\ninitial q1 = 0, q2 = 0, q1' = 1;\ntime 0 .. {};\n",
                e[0], e[1], e[2]
            )
        }
        1 => {
            let depth = 200 + rng.below(120);
            format!(
                "param x = {}1{};",
                "(".repeat(depth),
                ")".repeat(rng.below(depth + 2))
            )
        }
        2 => {
            let op = rng.word(&["+", "-", "*", "/", "^", "+-", "^-"]);
            // Mostly around the depth limit; rarely far beyond it (slow in debug).
            let terms = if rng.below(500) == 0 {
                100_000
            } else {
                rng.below(1500)
            };
            format!("lagrangian = {};", vec!["q1'"; terms.max(1)].join(op))
        }
        3 => format!("param x = {};", "-".repeat(rng.below(1500)) + "1"),
        4 => format!(
            "param x = {}{};",
            rng.word(&["1", "9", "0.", "1e"]),
            "9".repeat(rng.below(800))
        ),
        5 => {
            // Chains of conditionals and vectors, around the nesting limit
            // and rarely far beyond it.
            let n = if rng.below(200) == 0 {
                100_000
            } else {
                rng.below(400)
            };
            let case = rng.word(&[
                "if q1 < 1 then (q1, q2) else ",
                "if not q1 >= 0 and t < 1 then 2 else ",
                "(if q1 > 0 then 1 else ",
            ]);
            format!("coord q1, q2;\nlagrangian = {}q1;\n", case.repeat(n))
        }
        _ => return (0..rng.below(200)).map(|_| rng.next() as u8).collect(),
    };
    text.into_bytes()
}

/// Diagnostics must point inside the text they are rendered against.
fn assert_well_formed(input: &[u8]) {
    let (source, result) = lagc::check_and_derive_bytes(input);
    let Err(diagnostics) = result else {
        return;
    };
    assert!(!diagnostics.is_empty(), "Err without diagnostics");
    for d in &diagnostics {
        for label in &d.labels {
            assert!(
                label.span.start <= label.span.end && label.span.end <= source.len(),
                "{d:?}"
            );
            assert!(source.is_char_boundary(label.span.start), "{d:?}");
        }
    }
    // Rendering is the slow part in debug builds; long inputs are covered
    // by the parse and check above.
    if source.len() < 4_000 {
        diagnostic::render(&diagnostics, "fuzz.lag", &source, false);
    }
}

#[test]
fn no_input_panics() {
    let corpus = corpus();
    lagc::on_big_stack(|| {
        let mut rng = Rng::seeded(SEED);
        for n in 0..INPUTS {
            let input = if n % 4 == 3 {
                generated(&mut rng)
            } else {
                let base = rng.pick(&corpus).clone();
                mutate(&mut rng, base)
            };
            if catch_unwind(AssertUnwindSafe(|| assert_well_formed(&input))).is_err() {
                panic!(
                    "input {n} made the front end fail:\n{:?}",
                    String::from_utf8_lossy(&input)
                );
            }
        }
    });
}

/// Mutants through `check` alone (the derivation has its 12,000 above):
/// 100,000 a run, each with located diagnostics or a clean model.
const CHECK_INPUTS: usize = 100_000;

#[test]
fn no_input_panics_the_checker() {
    let corpus = corpus();
    lagc::on_big_stack(|| {
        let mut rng = Rng::seeded(SEED ^ 0x5eed_c4ec);
        for n in 0..CHECK_INPUTS {
            let input = if n % 8 == 7 {
                generated(&mut rng)
            } else {
                let base = rng.pick(&corpus).clone();
                mutate(&mut rng, base)
            };
            let checked = catch_unwind(AssertUnwindSafe(|| {
                let (source, result) = lagc::frontend_bytes(&input);
                if let Err(diagnostics) = result {
                    assert!(!diagnostics.is_empty(), "Err without diagnostics");
                    for d in &diagnostics {
                        for label in &d.labels {
                            assert!(label.span.end <= source.len(), "{d:?}");
                        }
                    }
                }
            }));
            if checked.is_err() {
                panic!(
                    "input {n} made the checker fail:\n{:?}",
                    String::from_utf8_lossy(&input)
                );
            }
        }
    });
}
