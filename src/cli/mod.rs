//! The IO of `lagc build` and `lagc run`: writing the generated crate,
//! the build cache, running cargo and the model's binary. Used only by
//! the binary's command handlers (`commands/`; the library does no IO).

pub mod args;
pub mod cache;
pub mod cargo;
pub mod commands;
pub mod progress;
pub mod report;
pub mod zip;

pub use cargo::cargo_build;
use lagc::emit::GeneratedCrate;
use std::path::{Path, PathBuf};
use std::process::{Command, ExitStatus};

/// Writes the crate under `dir`, leaving files whose contents are already
/// right untouched (so cargo sees no change and does not rebuild).
/// Each file is replaced whole (`cache::write_if_changed`).
pub fn write_crate(generated: &GeneratedCrate, dir: &Path) -> std::io::Result<()> {
    for (path, contents) in &generated.files {
        cache::write_if_changed(&dir.join(path), contents.as_bytes())?;
    }
    Ok(())
}

/// The largest model file lagc reads: a 50-link pendulum is 60 KB, so
/// 16 MiB is no model's limit, and stops a read of `/dev/zero`.
pub const MAX_MODEL_BYTES: u64 = 16 << 20;

/// A model file's bytes, at most [`MAX_MODEL_BYTES`] of them.
pub fn read_model_file(file: &Path) -> Result<Vec<u8>, String> {
    use std::io::Read;
    let handle = std::fs::File::open(file).map_err(|e| e.to_string())?;
    let mut bytes = Vec::new();
    handle
        .take(MAX_MODEL_BYTES + 1)
        .read_to_end(&mut bytes)
        .map_err(|e| e.to_string())?;
    if bytes.len() as u64 > MAX_MODEL_BYTES {
        return Err(format!(
            "it is larger than {} MiB, more than any model",
            MAX_MODEL_BYTES >> 20
        ));
    }
    Ok(bytes)
}

/// The file `lagc build -o DIR` leaves in DIR, so that a later build may
/// overwrite what an earlier one wrote, and nothing else.
pub const MARKER: &str = ".lagc-generated";

/// Whether `lagc build` may write into `dir`: it does not exist, is
/// empty, or holds the marker of an earlier build.
pub fn may_write_into(dir: &Path) -> bool {
    match std::fs::read_dir(dir) {
        Err(_) => !dir.exists(),
        Ok(mut entries) => entries.next().is_none() || dir.join(MARKER).is_file(),
    }
}

/// Where `lagc build -o DIR` puts the runtime's copy, inside DIR.
pub const RUNTIME_IN_CRATE: &str = "lagc-runtime";

/// Where `lagc build --python -o DIR` puts the `lagc-python` library's
/// copy, inside DIR.
pub const PYTHON_IN_PROJECT: &str = "lagc-python";

/// The cache's directory of the runtime (one per version of its sources).
pub fn runtime_dir_name() -> String {
    format!("runtime-{}", lagc::emit::runtime_version())
}

/// The runtime's path from a cached crate (`crates/<package>`).
pub fn runtime_path_from_cache() -> String {
    format!("../../{}", runtime_dir_name())
}

/// Writes the runtime crate's sources under `dir` (unchanged files are not
/// rewritten, so cargo does not rebuild it).
pub fn write_runtime(dir: &Path) -> std::io::Result<()> {
    for (path, contents) in lagc::emit::runtime_files() {
        cache::write_if_changed(&dir.join(path), contents.as_bytes())?;
    }
    remove_stale_sources(dir)
}

/// Removes the `.rs` files under `dir/src` that are not the runtime's: an
/// earlier version's, where a module has since moved (`src/method.rs`
/// beside the new `src/method/mod.rs` does not build).
fn remove_stale_sources(dir: &Path) -> std::io::Result<()> {
    let known: std::collections::HashSet<std::path::PathBuf> = lagc::emit::runtime_files()
        .map(|(path, _)| dir.join(path))
        .collect();
    let mut folders = vec![dir.join("src")];
    while let Some(folder) = folders.pop() {
        let Ok(entries) = std::fs::read_dir(&folder) else {
            continue;
        };
        for entry in entries {
            let path = entry?.path();
            if path.is_dir() {
                folders.push(path);
            } else if path.extension().is_some_and(|e| e == "rs") && !known.contains(&path) {
                std::fs::remove_file(&path)?;
            }
        }
    }
    Ok(())
}

/// A hash of a model's source and of lagc's version (FNV-1a), which the
/// generated binary reports with `--lagc-source-hash`.
pub fn source_hash(source: &str) -> String {
    let version = concat!(env!("CARGO_PKG_VERSION"), "\0");
    let runtime = lagc::emit::runtime_version();
    let hash = lagc::emit::fnv1a(version.bytes().chain(runtime.bytes()).chain(source.bytes()));
    format!("{hash:016x}")
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

/// Runs the built binary with `args`, its stdout and stderr ours.
/// The source hash a generated binary reports (`--lagc-source-hash`), or
/// `None` when it does not run or answers otherwise.
pub fn binary_hash(binary: &Path) -> Option<String> {
    let output = Command::new(binary)
        .arg("--lagc-source-hash")
        .output()
        .ok()?;
    if !output.status.success() {
        return None;
    }
    Some(String::from_utf8(output.stdout).ok()?.trim().to_string())
}

/// Sets a file's modification time to now (ignoring failure: the rebuild
/// that follows reports what matters).
pub fn touch(file: &Path) {
    if let Ok(handle) = std::fs::OpenOptions::new().append(true).open(file) {
        let _ = handle.set_modified(std::time::SystemTime::now());
    }
}

/// A key for a model file's crate in the cache: a hash of its canonical
/// path (the file's text may change; its crate is rebuilt in place).
pub fn path_key(file: &Path) -> String {
    let path = std::fs::canonicalize(file).unwrap_or_else(|_| file.to_path_buf());
    let hash = lagc::emit::fnv1a(path.to_string_lossy().bytes());
    format!("{:08x}", hash >> 32)
}

pub fn run_binary(binary: &Path, args: &[String]) -> std::io::Result<ExitStatus> {
    Command::new(binary).args(args).status()
}

/// The path of `to` as seen from the directory `from` (both existing):
/// relative when they share a root, else `to` made absolute.
pub fn relative_path(from: &Path, to: &Path) -> String {
    let (Ok(from), Ok(to)) = (from.canonicalize(), to.canonicalize()) else {
        return to.display().to_string();
    };
    let common = from
        .components()
        .zip(to.components())
        .take_while(|(a, b)| a == b)
        .count();
    if common == 0 {
        return to.display().to_string();
    }
    let mut path = PathBuf::new();
    for _ in from.components().skip(common) {
        path.push("..");
    }
    for part in to.components().skip(common) {
        path.push(part);
    }
    if path.as_os_str().is_empty() {
        ".".to_string()
    } else {
        path.display().to_string()
    }
}
