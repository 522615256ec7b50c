//! The README's program that uses two generated crates: built with
//! `lagc build --runtime` exactly as the README says, from the README's own
//! code blocks, and run.

use std::path::Path;
use std::process::Command;

/// The code block after the line `after` in the README.
fn block_after(readme: &str, after: &str) -> String {
    let start = readme
        .find(after)
        .unwrap_or_else(|| panic!("README lacks {after:?}"));
    let rest = &readme[start..];
    let open = rest.find("```").unwrap();
    let body_start = open + rest[open..].find('\n').unwrap() + 1;
    let close = body_start + rest[body_start..].find("```").unwrap();
    rest[body_start..close].to_string()
}

fn lagc_build(model: &str, out: &Path, runtime: &Path) {
    let output = Command::new(env!("CARGO_BIN_EXE_lagc"))
        .args(["build", model, "-o"])
        .arg(out)
        .arg("--runtime")
        .arg(runtime)
        .arg("--force")
        .current_dir(crate::root())
        .output()
        .unwrap();
    assert!(
        output.status.success(),
        "{}",
        String::from_utf8_lossy(&output.stderr)
    );
}

#[test]
fn the_readme_program_uses_two_models_together() {
    let root = crate::root();
    let readme = std::fs::read_to_string(root.join("README.md")).unwrap();
    let models = root.join("target/readme-models");
    let runtime = models.join("lagc-runtime");
    lagc_build("examples/paper.lag", &models.join("paper"), &runtime);
    lagc_build(
        "examples/vertical_rocket.lag",
        &models.join("rocket"),
        &runtime,
    );
    let app = models.join("app");
    std::fs::create_dir_all(app.join("src")).unwrap();
    std::fs::write(
        app.join("Cargo.toml"),
        block_after(&readme, "`models/app/Cargo.toml`"),
    )
    .unwrap();
    std::fs::write(
        app.join("src/main.rs"),
        block_after(&readme, "`models/app/src/main.rs`"),
    )
    .unwrap();
    let target = root.join("target/generated-crates/target");
    crate::generated::cargo_build(&app.join("Cargo.toml"), &target, "the README's program");
    let ran = Command::new(target.join("release/two-models"))
        .output()
        .unwrap();
    let stdout = String::from_utf8_lossy(&ran.stdout);
    assert!(
        ran.status.success(),
        "{}",
        String::from_utf8_lossy(&ran.stderr)
    );
    assert_eq!(
        stdout,
        "paper: q1(5) = 7.267018147514\n\
         paper, q1'(0) = 2: q1(5) = 14.534036295027\n\
         rocket: z(80) = 88136.104378\n",
        "the README's stated output"
    );
}
