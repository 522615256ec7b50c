//! Building a generated crate with cargo, and cargo's failures in lagc's
//! words: a full disk, a cache that cannot be written, a missing linker,
//! a dependency missing offline. cargo's own output still streams to
//! stderr as it comes (its progress), and stays above the explanation.

use std::io::{BufRead, BufReader, Write};
use std::path::Path;
use std::process::{Command, ExitStatus, Stdio};

/// How a build ended: cargo's status and the last lines it wrote.
pub struct CargoBuild {
    pub status: ExitStatus,
    pub tail: Vec<String>,
}

/// Lines of cargo's stderr kept for the explanation.
const TAIL: usize = 200;

/// `cargo build --release --offline` of the crate in `crate_dir` with the
/// shared target directory.
pub fn cargo_build(crate_dir: &Path, target_dir: &Path) -> std::io::Result<CargoBuild> {
    let cargo = std::env::var_os("CARGO").unwrap_or_else(|| "cargo".into());
    let mut child = Command::new(cargo)
        .arg("build")
        .arg("--release")
        // Generated crates depend only on the runtime next to them: no
        // network, ever.
        .arg("--offline")
        .arg("--manifest-path")
        .arg(crate_dir.join("Cargo.toml"))
        .env("CARGO_TARGET_DIR", target_dir)
        .stderr(Stdio::piped())
        .spawn()?;
    let mut tail = std::collections::VecDeque::with_capacity(TAIL);
    if let Some(stderr) = child.stderr.take() {
        let mut ours = std::io::stderr();
        for line in BufReader::new(stderr).lines() {
            let Ok(line) = line else { break };
            let _ = writeln!(ours, "{line}");
            if tail.len() == TAIL {
                tail.pop_front();
            }
            tail.push_back(line);
        }
    }
    Ok(CargoBuild {
        status: child.wait()?,
        tail: tail.into(),
    })
}

/// What went wrong, in lagc's words, from cargo's last lines; `cache` is
/// the cache directory the build wrote into.
pub fn explain(tail: &[String], cache: &Path) -> String {
    let text = tail.join("\n");
    let has = |needle: &str| text.contains(needle);
    let cache = cache.display();
    if has("No space left on device") {
        format!("the disk holding the cache `{cache}` is full; free space or set LAGC_CACHE_DIR to another disk")
    } else if has("Read-only file system") || has("Permission denied") {
        format!("the cache `{cache}` cannot be written; set LAGC_CACHE_DIR to a writable directory")
    } else if has("File name too long") {
        format!("a path under the cache `{cache}` is too long for the file system; set LAGC_CACHE_DIR to a shorter directory")
    } else if has("linker `cc` not found")
        || has("linker `cc`")
        || has("could not execute process `cc`")
    {
        "no C linker (`cc`) was found, which Rust needs to link the model's binary; install a C toolchain (e.g. Debian's `build-essential`)".to_string()
    } else if has("--offline") || has("failed to get") || has("no matching package") {
        "a dependency of the generated crate is missing and lagc builds offline; this is a bug in lagc (generated crates depend only on the runtime it writes), please report it".to_string()
    } else if has("error[E") || has("could not compile") {
        "the generated code does not compile; this is a bug in lagc, please report it with the model".to_string()
    } else {
        "cargo failed to build the generated crate; its output is above".to_string()
    }
}

#[cfg(test)]
mod tests {
    use super::explain;
    use std::path::Path;

    fn cause(line: &str) -> String {
        explain(&[line.to_string()], Path::new("/c"))
    }

    #[test]
    fn each_known_failure_gets_its_cause() {
        assert!(cause("error: No space left on device (os error 28)").contains("is full"));
        assert!(cause("error: Read-only file system (os error 30)").contains("cannot be written"));
        assert!(cause("Permission denied (os error 13)").contains("LAGC_CACHE_DIR"));
        assert!(cause("File name too long (os error 36)").contains("too long"));
        assert!(cause("error: linker `cc` not found").contains("C linker"));
        assert!(cause("error[E0308]: mismatched types").contains("bug in lagc"));
        assert!(cause("something else").contains("output is above"));
    }
}
