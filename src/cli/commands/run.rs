//! `lagc run`: the crate built in the cache (once per model and runtime
//! version, under locks) and its binary run with the options as given.

use super::{generate_cached, EXIT_USAGE};
use crate::cli::args::RunArgs;
use std::path::{Path, PathBuf};
use std::process::ExitCode;

/// `lagc run`'s own option, taken out of the options passed on: the
/// model's notes on every run, not only when its crate is built.
const VERBOSE: &str = "--verbose";

const VERBOSE_USAGE: &str = concat!(
    "  --verbose              (lagc run) show the model's notes (N0001: the\n",
    "                         local field method) on every run, not only when\n",
    "                         lagc builds its crate"
);

pub(crate) fn run(args: &RunArgs) -> ExitCode {
    let (generated, notes) = match generate_cached(&args.file) {
        Ok(generated) => generated,
        Err(status) => return status,
    };
    let verbose = args.args.iter().any(|a| a == VERBOSE);
    let options: Vec<String> = args
        .args
        .iter()
        .filter(|a| *a != VERBOSE)
        .cloned()
        .collect();
    // The model's binary parses its options; the same parser checks them
    // here first, so that bad usage is reported before anything is built.
    // They are passed on as they came.
    let params: Vec<&str> = generated.params.iter().map(String::as_str).collect();
    let state: Vec<&str> = generated.state.iter().map(String::as_str).collect();
    let outputs: Vec<&str> = generated.outputs.iter().map(String::as_str).collect();
    let parsed = lagc_runtime::cli::parse(&options, &params, &state, &outputs);
    match parsed {
        Err(message) => {
            eprintln!(
                "error: {message}\n\n{}\n{VERBOSE_USAGE}",
                lagc_runtime::cli::USAGE
            );
            return ExitCode::from(EXIT_USAGE);
        }
        Ok(lagc_runtime::cli::Command::Help) => {
            println!("{}\n{VERBOSE_USAGE}", lagc_runtime::cli::USAGE);
            return ExitCode::SUCCESS;
        }
        Ok(_) => {}
    }
    // The notes once per build: when this model's binary is not in the
    // cache yet (new, changed, or built by another lagc), or when asked.
    // They hold about nine lines for every non-affine model.
    if verbose || !built(&generated) {
        eprint!("{notes}");
    }
    let binary = match build_cached(&generated, &args.file) {
        Ok(binary) => binary,
        Err(status) => return status,
    };
    match crate::cli::run_binary(&binary, &options) {
        Ok(status) => match status.code() {
            Some(code) => ExitCode::from(u8::try_from(code).unwrap_or(1)),
            None => ExitCode::FAILURE,
        },
        Err(error) => {
            eprintln!("error: cannot run `{}`: {error}", binary.display());
            ExitCode::FAILURE
        }
    }
}

/// Whether the cache holds this model's binary, built from this very
/// source by this lagc and runtime (it answers the source hash).
fn built(generated: &lagc::emit::GeneratedCrate) -> bool {
    let Some(cache) = crate::cli::cache_dir() else {
        return false;
    };
    let binary = cache.join("target").join("release").join(format!(
        "{}{}",
        generated.package,
        std::env::consts::EXE_SUFFIX
    ));
    binary.is_file()
        && crate::cli::binary_hash(&binary).as_deref() == Some(generated.source_hash.as_str())
}

/// Writes the crate into the cache and builds it there; the binary's path.
pub(crate) fn build_cached(
    generated: &lagc::emit::GeneratedCrate,
    model_file: &Path,
) -> Result<PathBuf, ExitCode> {
    let Some(cache) = crate::cli::cache_dir() else {
        eprintln!("error: no cache directory: set LAGC_CACHE_DIR (or XDG_CACHE_HOME or HOME)");
        return Err(ExitCode::from(EXIT_USAGE));
    };
    let crate_dir = cache.join("crates").join(&generated.package);
    let target_dir = cache.join("target");
    // Other lagc processes may run this model, or others, right now: the
    // runtime is written under its lock, and this crate is written, built
    // and checked under its own (held until this function returns).
    let runtime = crate::cli::runtime_dir_name();
    let waiting = |what: String| {
        move || eprintln!("note: waiting for another lagc process that is building {what}")
    };
    let written = crate::cli::cache::lock(&cache, &runtime, waiting("the runtime".to_string()))
        .and_then(|_lock| {
            crate::cli::cache::remove_temporaries(&cache.join(&runtime));
            crate::cli::write_runtime(&cache.join(&runtime))
        });
    let locked = written.and_then(|()| {
        crate::cli::cache::lock(
            &cache,
            &generated.package,
            waiting(format!("`{}`", generated.package)),
        )
    });
    let _lock = match locked {
        Ok(lock) => lock,
        Err(error) => {
            eprintln!("error: cannot write to `{}`: {error}", cache.display());
            return Err(ExitCode::from(EXIT_USAGE));
        }
    };
    crate::cli::cache::remove_temporaries(&crate_dir);
    let source = model_file
        .canonicalize()
        .unwrap_or_else(|_| model_file.to_path_buf());
    let written = crate::cli::write_crate(generated, &crate_dir)
        .and_then(|()| {
            crate::cli::cache::write_if_changed(
                &crate_dir.join(crate::cli::cache::SOURCE),
                source.display().to_string().as_bytes(),
            )
        })
        .and_then(|_| std::fs::write(crate_dir.join(crate::cli::cache::LAST_RUN), ""));
    if let Err(error) = written {
        eprintln!("error: cannot write to `{}`: {error}", crate_dir.display());
        return Err(ExitCode::from(EXIT_USAGE));
    }
    match crate::cli::cargo_build(&crate_dir, &target_dir) {
        Ok(build) if build.status.success() => {}
        Ok(build) => {
            // Not the model's fault (exit 1 says that): the machine's.
            eprintln!(
                "error: the generated crate could not be built ({}): {}",
                build.status,
                crate::cli::cargo::explain(&build.tail, &cache)
            );
            return Err(ExitCode::from(EXIT_USAGE));
        }
        Err(error) => {
            eprintln!(
                "error: cannot run cargo ({error}); lagc needs Rust's cargo on the PATH (or in $CARGO)"
            );
            return Err(ExitCode::from(EXIT_USAGE));
        }
    }
    let binary = target_dir.join("release").join(format!(
        "{}{}",
        generated.package,
        std::env::consts::EXE_SUFFIX
    ));
    // The binary must be this model's: a binary copied in, damaged, or
    // left by another build is removed and built again (cargo rebuilds a
    // missing output), and refused if it still does not answer.
    for attempt in 0..2 {
        if crate::cli::binary_hash(&binary).as_deref() == Some(generated.source_hash.as_str()) {
            let removed = crate::cli::cache::evict(
                &cache,
                cache_bound(),
                &crate::cli::runtime_dir_name(),
                &generated.package,
            );
            if !removed.is_empty() {
                eprintln!(
                    "note: the cache outgrew its bound; removed the {} least recently run model(s)",
                    removed.len()
                );
            }
            return Ok(binary);
        }
        if attempt == 0 {
            eprintln!(
                "note: `{}` is not this model's binary (damaged or replaced); rebuilding it",
                binary.display()
            );
            // The uplifted binary may share its inode with cargo's own
            // copy; a fresh source time makes cargo rebuild both.
            let _ = std::fs::remove_file(&binary);
            crate::cli::touch(&crate_dir.join("src/main.rs"));
            match crate::cli::cargo_build(&crate_dir, &target_dir) {
                Ok(build) if build.status.success() => {}
                _ => break,
            }
        }
    }
    eprintln!(
        "error: `{}` does not belong to this model even after a rebuild; remove the cache \
         directory `{}` and run again",
        binary.display(),
        cache.display()
    );
    Err(ExitCode::FAILURE)
}

/// The cache's size bound: `$LAGC_CACHE_MAX_BYTES`, or the default.
pub(crate) fn cache_bound() -> u64 {
    std::env::var("LAGC_CACHE_MAX_BYTES")
        .ok()
        .and_then(|v| v.trim().parse().ok())
        .unwrap_or(crate::cli::cache::DEFAULT_MAX_BYTES)
}
