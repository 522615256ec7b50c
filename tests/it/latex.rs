//! `lagc derive --format latex` goes into a paper: every example's block
//! compiles with a real TeX engine, and long equations are broken so that
//! none runs far off the page. Skipped, saying so, where no `pdflatex` is
//! installed (Debian: texlive-latex-base, texlive-latex-recommended).

use std::process::Command;

/// The widest line allowed past the text width, in TeX points (the 3-D
/// rolling disk's longest unbreakable factor is 176 pt).
const OVERFULL_LIMIT_PT: f64 = 200.0;

#[test]
fn every_examples_latex_compiles_and_fits_the_page() {
    if Command::new("pdflatex").arg("--version").output().is_err() {
        eprintln!("SKIPPED: no pdflatex on this machine (install texlive-latex-base)");
        return;
    }
    let root = crate::root();
    let dir = root.join("target/latex-tests");
    std::fs::create_dir_all(&dir).unwrap();
    let mut examples: Vec<_> = std::fs::read_dir(root.join("examples"))
        .unwrap()
        .filter_map(|e| e.ok().map(|e| e.path()))
        .filter(|p| p.extension().is_some_and(|e| e == "lag"))
        .collect();
    examples.sort();
    for path in examples {
        let name = path.file_stem().unwrap().to_string_lossy().into_owned();
        let derived = Command::new(env!("CARGO_BIN_EXE_lagc"))
            .args(["derive", "--format", "latex"])
            .arg(&path)
            .output()
            .unwrap();
        assert!(derived.status.success(), "{name}: derive failed");
        let block = String::from_utf8(derived.stdout).unwrap();
        assert!(
            block.contains("(4)") || block.contains("(7)"),
            "{name}: {block}"
        );
        let document = format!(
            "\\documentclass{{article}}\\usepackage{{amsmath}}\\allowdisplaybreaks\n\
             \\usepackage[margin=2cm]{{geometry}}\\begin{{document}}\n{block}\\end{{document}}\n"
        );
        std::fs::write(dir.join(format!("{name}.tex")), document).unwrap();
        let tex = Command::new("pdflatex")
            .args(["-interaction=nonstopmode", "-halt-on-error"])
            .arg(format!("{name}.tex"))
            .current_dir(&dir)
            .output()
            .unwrap();
        let log = String::from_utf8_lossy(&tex.stdout);
        assert!(tex.status.success(), "{name}: pdflatex failed:\n{log}");
        let widest = log
            .lines()
            .filter_map(|l| l.strip_prefix("Overfull \\hbox ("))
            .filter_map(|l| l.split("pt").next()?.parse::<f64>().ok())
            .fold(0.0, f64::max);
        assert!(
            widest <= OVERFULL_LIMIT_PT,
            "{name}: a line runs {widest} pt past the text width"
        );
    }
}

/// `lagc derive` of `path` in `format`.
fn derive(path: &std::path::Path, format: &str) -> String {
    let derived = Command::new(env!("CARGO_BIN_EXE_lagc"))
        .args(["derive", "--format", format])
        .arg(path)
        .output()
        .unwrap();
    assert!(
        derived.status.success(),
        "{}: derive failed",
        path.display()
    );
    String::from_utf8(derived.stdout).unwrap()
}

/// Issue 13: one notation for time derivatives, the language's own
/// (Lagrange's): primes through the third (`q'`, `q''`, `q'''`, the
/// coefficients' `f_{2}'` too), `q^{(n)}` from the fourth, never a dot; a
/// derivative raised to a power is braced (`{a'}^{2}`, `{x^{(4)}}^{2}`),
/// and every line's `&=` stands apart from its left side.
#[test]
fn latex_writes_derivatives_one_way() {
    let root = crate::root();
    let mut files: Vec<_> = std::fs::read_dir(root.join("examples"))
        .unwrap()
        .filter_map(|e| e.ok().map(|e| e.path()))
        .filter(|p| p.extension().is_some_and(|e| e == "lag"))
        .collect();
    files.sort();
    files.push(root.join("tests/data/fourth_order_constraint.lag"));
    for path in &files {
        let block = derive(path, "latex");
        for wrong in ["\\dot", "\\ddot", "''''", ")}^{", "'^", "}&="] {
            assert!(
                !block.contains(wrong),
                "{}: {wrong} in\n{block}",
                path.display()
            );
        }
    }
    let fourth = root.join("tests/data/fourth_order_constraint.lag");
    insta::assert_snapshot!("fourth_order_latex", derive(&fourth, "latex"));
    insta::assert_snapshot!("fourth_order_text", derive(&fourth, "text"));
    // The examples' blocks are snapshots of `mechanics::examples`.
}
