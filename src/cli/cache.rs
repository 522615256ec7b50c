//! `lagc cache list|clean` and the cache's size bound: each model's crate
//! under `crates/`, its binary and artifacts in the shared `target/`, one
//! runtime per lagc version. The least recently run models go first when
//! the cache outgrows its bound.
//!
//! Several `lagc` processes may use one cache at once. Each cached crate
//! (and each runtime) has a lock file under `locks/`, held exclusively
//! (`File::lock`, released by the OS when a process dies, so a killed
//! build leaves no stale lock) while the crate is written, built and its
//! binary checked; eviction skips a crate whose lock another process holds.
//! Every file is written to a temporary file and renamed over the old one,
//! and every run compares each file with what it should hold, so a run
//! killed half-way leaves files that are wholly old or wholly new, and the
//! next run rewrites whatever differs and lets cargo rebuild.

use std::fs::{File, TryLockError};
use std::path::{Path, PathBuf};
use std::time::SystemTime;

/// The file in a model's crate directory whose time says when it last ran.
pub const LAST_RUN: &str = ".lagc-last-run";
/// The file in a model's crate directory naming the model it was built from.
pub const SOURCE: &str = ".lagc-source";
/// The default bound on the cache's size (`LAGC_CACHE_MAX_BYTES` overrides).
pub const DEFAULT_MAX_BYTES: u64 = 4_000_000_000;

/// The directory of the lock files, beside `crates/`.
pub const LOCKS: &str = "locks";

/// An exclusive lock on one cached crate or runtime, held until dropped.
#[derive(Debug)]
pub struct Lock {
    _file: File,
}

fn lock_file(cache: &Path, name: &str) -> std::io::Result<File> {
    let dir = cache.join(LOCKS);
    std::fs::create_dir_all(&dir)?;
    std::fs::OpenOptions::new()
        .create(true)
        .truncate(false)
        .write(true)
        .open(dir.join(format!("{name}.lock")))
}

/// The lock on `name` (a package, or the runtime's directory name),
/// waiting for another process that holds it; `waiting` is called once
/// when it must wait.
pub fn lock(cache: &Path, name: &str, waiting: impl FnOnce()) -> std::io::Result<Lock> {
    let file = lock_file(cache, name)?;
    match file.try_lock() {
        Ok(()) => {}
        Err(TryLockError::WouldBlock) => {
            waiting();
            file.lock()?;
        }
        Err(TryLockError::Error(e)) => return Err(e),
    }
    Ok(Lock { _file: file })
}

/// The lock on `name` if no other process holds it.
pub fn try_lock(cache: &Path, name: &str) -> Option<Lock> {
    let file = lock_file(cache, name).ok()?;
    file.try_lock().ok()?;
    Some(Lock { _file: file })
}

/// Writes `contents` to `target` unless it holds them already, through a
/// temporary file renamed over it: a reader (cargo in another process)
/// and a run killed half-way never see a half-written file. Returns
/// whether it wrote.
pub fn write_if_changed(target: &Path, contents: &[u8]) -> std::io::Result<bool> {
    if std::fs::read(target).is_ok_and(|old| old == contents) {
        return Ok(false);
    }
    if let Some(parent) = target.parent() {
        std::fs::create_dir_all(parent)?;
    }
    let name = target
        .file_name()
        .map(|n| n.to_string_lossy().into_owned())
        .unwrap_or_default();
    let temporary = target.with_file_name(format!(".{name}.lagc-tmp-{}", std::process::id()));
    let written =
        std::fs::write(&temporary, contents).and_then(|()| std::fs::rename(&temporary, target));
    if written.is_err() {
        let _ = std::fs::remove_file(&temporary);
    }
    written.map(|()| true)
}

/// Removes the temporary files a killed writer left in `dir` and its
/// subdirectories (the caller holds the lock, so no writer is alive).
pub fn remove_temporaries(dir: &Path) {
    let mut stack = vec![dir.to_path_buf()];
    while let Some(dir) = stack.pop() {
        let Ok(entries) = std::fs::read_dir(&dir) else {
            continue;
        };
        for entry in entries.flatten() {
            let name = entry.file_name().to_string_lossy().into_owned();
            if entry.file_type().is_ok_and(|t| t.is_dir()) {
                stack.push(entry.path());
            } else if name.starts_with('.') && name.contains(".lagc-tmp-") {
                let _ = std::fs::remove_file(entry.path());
            }
        }
    }
}

/// The bytes under `path` (0 if it is missing).
pub fn size(path: &Path) -> u64 {
    let Ok(meta) = std::fs::symlink_metadata(path) else {
        return 0;
    };
    if !meta.is_dir() {
        return meta.len();
    }
    let mut total = 0;
    let mut stack = vec![path.to_path_buf()];
    while let Some(dir) = stack.pop() {
        let Ok(entries) = std::fs::read_dir(&dir) else {
            continue;
        };
        for entry in entries.flatten() {
            match entry.metadata() {
                Ok(m) if m.is_dir() => stack.push(entry.path()),
                Ok(m) => total += m.len(),
                Err(_) => {}
            }
        }
    }
    total
}

/// One model in the cache.
#[derive(Debug, Clone)]
pub struct Entry {
    pub package: String,
    /// The model file it was built from, when recorded.
    pub source: Option<String>,
    pub last_run: Option<SystemTime>,
    /// Its crate, binary and build artifacts.
    pub bytes: u64,
}

/// The paths one package owns in the shared target directory.
fn artifacts(cache: &Path, package: &str) -> Vec<PathBuf> {
    let release = cache.join("target").join("release");
    let library = package.replace('-', "_");
    let mut paths = vec![
        release.join(format!("{package}{}", std::env::consts::EXE_SUFFIX)),
        release.join(format!("{package}.d")),
    ];
    for (dir, prefixes) in [
        (
            "deps",
            vec![format!("{library}-"), format!("lib{library}-")],
        ),
        (".fingerprint", vec![format!("{package}-")]),
        ("build", vec![format!("{package}-")]),
        ("incremental", vec![format!("{library}-")]),
    ] {
        if let Ok(entries) = std::fs::read_dir(release.join(dir)) {
            for entry in entries.flatten() {
                let name = entry.file_name().to_string_lossy().into_owned();
                if prefixes.iter().any(|p| name.starts_with(p)) {
                    paths.push(entry.path());
                }
            }
        }
    }
    paths
}

/// Every model in the cache, least recently run first.
pub fn entries(cache: &Path) -> Vec<Entry> {
    let mut entries = Vec::new();
    let Ok(dirs) = std::fs::read_dir(cache.join("crates")) else {
        return entries;
    };
    for dir in dirs.flatten() {
        let package = dir.file_name().to_string_lossy().into_owned();
        let path = dir.path();
        let last_run = std::fs::metadata(path.join(LAST_RUN))
            .and_then(|m| m.modified())
            .ok();
        let source = std::fs::read_to_string(path.join(SOURCE))
            .ok()
            .map(|s| s.trim().to_string());
        let bytes = size(&path)
            + artifacts(cache, &package)
                .iter()
                .map(|p| size(p))
                .sum::<u64>();
        entries.push(Entry {
            package,
            source,
            last_run,
            bytes,
        });
    }
    entries.sort_by_key(|e| (e.last_run, e.package.clone()));
    entries
}

/// Removes one model's crate and artifacts (the caller holds its lock).
pub fn remove(cache: &Path, package: &str) -> std::io::Result<()> {
    for path in artifacts(cache, package) {
        let removed = if path.is_dir() {
            std::fs::remove_dir_all(&path)
        } else {
            std::fs::remove_file(&path)
        };
        if let Err(e) = removed {
            if e.kind() != std::io::ErrorKind::NotFound {
                return Err(e);
            }
        }
    }
    std::fs::remove_dir_all(cache.join("crates").join(package))
}

/// Runtimes of other lagc versions than `current` (a directory name).
pub fn stale_runtimes(cache: &Path, current: &str) -> Vec<PathBuf> {
    let Ok(entries) = std::fs::read_dir(cache) else {
        return Vec::new();
    };
    entries
        .flatten()
        .filter(|e| {
            let name = e.file_name().to_string_lossy().into_owned();
            name.starts_with("runtime-") && name != current
        })
        .map(|e| e.path())
        .collect()
}

/// Keeps the cache under `max_bytes`: removes other versions' runtimes,
/// then the least recently run models (never `keep`, the one just built).
/// Returns the packages removed.
pub fn evict(cache: &Path, max_bytes: u64, current_runtime: &str, keep: &str) -> Vec<String> {
    let mut removed = Vec::new();
    if size(cache) <= max_bytes {
        return removed;
    }
    for stale in stale_runtimes(cache, current_runtime) {
        // Another lagc version may be building with it right now.
        let name = stale.file_name().map(|n| n.to_string_lossy().into_owned());
        if let Some(_lock) = name.and_then(|n| try_lock(cache, &n)) {
            let _ = std::fs::remove_dir_all(stale);
        }
    }
    for entry in entries(cache) {
        if size(cache) <= max_bytes {
            break;
        }
        if entry.package == keep {
            continue;
        }
        // Another process is writing or building it: not ours to remove.
        let Some(_lock) = try_lock(cache, &entry.package) else {
            continue;
        };
        if remove(cache, &entry.package).is_ok() {
            removed.push(entry.package);
        }
    }
    removed
}

/// A size in words: `12.3 MB`.
pub fn human(bytes: u64) -> String {
    let units = ["B", "kB", "MB", "GB", "TB"];
    let mut value = bytes as f64;
    let mut unit = 0;
    while value >= 1000.0 && unit + 1 < units.len() {
        value /= 1000.0;
        unit += 1;
    }
    if unit == 0 {
        format!("{bytes} B")
    } else {
        format!("{value:.1} {}", units[unit])
    }
}

/// How long ago `time` was, in words.
pub fn age(time: Option<SystemTime>) -> String {
    let Some(time) = time else {
        return "never run".to_string();
    };
    let seconds = SystemTime::now()
        .duration_since(time)
        .map(|d| d.as_secs())
        .unwrap_or(0);
    match seconds {
        s if s < 120 => format!("{s} s ago"),
        s if s < 7200 => format!("{} min ago", s / 60),
        s if s < 172_800 => format!("{} h ago", s / 3600),
        s => format!("{} days ago", s / 86_400),
    }
}
