//! The IO of `lagc build` and `lagc run`: writing the generated crate,
//! the build cache, running cargo and the model's binary. Used only by
//! `main.rs` (the library does no IO).

pub mod progress;
pub mod report;

use lagc::emit::GeneratedCrate;
use std::path::{Path, PathBuf};
use std::process::{Command, ExitStatus};

/// Writes the crate under `dir`, leaving files whose contents are already
/// right untouched (so cargo sees no change and does not rebuild).
pub fn write_crate(generated: &GeneratedCrate, dir: &Path) -> std::io::Result<()> {
    for (path, contents) in &generated.files {
        let target = dir.join(path);
        if let Some(parent) = target.parent() {
            std::fs::create_dir_all(parent)?;
        }
        if std::fs::read(&target).is_ok_and(|old| old == contents.as_bytes()) {
            continue;
        }
        std::fs::write(&target, contents)?;
    }
    Ok(())
}

/// `$LAGC_CACHE_DIR`, or `$XDG_CACHE_HOME/lagc`, or `~/.cache/lagc`.
pub fn cache_dir() -> Option<PathBuf> {
    let non_empty = |name: &str| std::env::var_os(name).filter(|v| !v.is_empty());
    if let Some(dir) = non_empty("LAGC_CACHE_DIR") {
        return Some(PathBuf::from(dir));
    }
    if let Some(dir) = non_empty("XDG_CACHE_HOME") {
        return Some(PathBuf::from(dir).join("lagc"));
    }
    non_empty("HOME").map(|home| PathBuf::from(home).join(".cache").join("lagc"))
}

/// `cargo build --release` of the crate in `crate_dir` with the shared
/// target directory; cargo's progress goes to our stderr.
pub fn cargo_build(crate_dir: &Path, target_dir: &Path) -> std::io::Result<ExitStatus> {
    let cargo = std::env::var_os("CARGO").unwrap_or_else(|| "cargo".into());
    Command::new(cargo)
        .arg("build")
        .arg("--release")
        .arg("--manifest-path")
        .arg(crate_dir.join("Cargo.toml"))
        .env("CARGO_TARGET_DIR", target_dir)
        .status()
}

/// Runs the built binary with `args`, its stdout and stderr ours.
pub fn run_binary(binary: &Path, args: &[String]) -> std::io::Result<ExitStatus> {
    Command::new(binary).args(args).status()
}
