//! `lagc cache list|clean`.

use super::run::cache_bound;
use super::EXIT_USAGE;
use crate::cli::args::{CacheAction, CacheArgs};
use std::process::ExitCode;

pub(crate) fn cache(args: &CacheArgs) -> ExitCode {
    let Some(cache) = crate::cli::cache_dir() else {
        eprintln!("error: no cache directory: set LAGC_CACHE_DIR (or XDG_CACHE_HOME or HOME)");
        return ExitCode::from(EXIT_USAGE);
    };
    match args.action {
        CacheAction::List => {
            let entries = crate::cli::cache::entries(&cache);
            println!("cache: {}", cache.display());
            for e in entries.iter().rev() {
                println!(
                    "  {:<40} {:>9}  {:<14} {}",
                    e.package,
                    crate::cli::cache::human(e.bytes),
                    crate::cli::cache::age(e.last_run),
                    e.source.as_deref().unwrap_or("(model file not recorded)")
                );
            }
            println!(
                "{} model(s); {} in all (bound {})",
                entries.len(),
                crate::cli::cache::human(crate::cli::cache::size(&cache)),
                crate::cli::cache::human(cache_bound())
            );
            ExitCode::SUCCESS
        }
        CacheAction::Clean => {
            let bytes = crate::cli::cache::size(&cache);
            match std::fs::remove_dir_all(&cache) {
                Ok(()) => {
                    eprintln!(
                        "removed {} ({})",
                        cache.display(),
                        crate::cli::cache::human(bytes)
                    );
                    ExitCode::SUCCESS
                }
                Err(e) if e.kind() == std::io::ErrorKind::NotFound => {
                    eprintln!("the cache {} is empty", cache.display());
                    ExitCode::SUCCESS
                }
                Err(e) => {
                    eprintln!("error: cannot remove `{}`: {e}", cache.display());
                    ExitCode::from(EXIT_USAGE)
                }
            }
        }
    }
}
