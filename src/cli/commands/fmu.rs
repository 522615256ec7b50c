//! `lagc build FILE --fmu -o NAME.fmu`: the model's FMU crate built by
//! cargo in the cache (beside copies of the runtime and the lagc-fmu
//! library, with a target directory of their own, so the two compile once),
//! its shared library zipped with modelDescription.xml.

use super::EXIT_USAGE;
use crate::cli::args::BuildArgs;
use std::path::Path;
use std::process::ExitCode;

pub(crate) fn build_fmu(args: &BuildArgs) -> ExitCode {
    let Some(cache) = crate::cli::cache_dir() else {
        eprintln!("error: no cache directory (set LAGC_CACHE_DIR or HOME)");
        return ExitCode::from(EXIT_USAGE);
    };
    if std::env::consts::OS != "linux" || std::env::consts::ARCH != "x86_64" {
        eprintln!("error: `--fmu` builds FMUs for Linux x86-64 only, on such a machine");
        return ExitCode::from(EXIT_USAGE);
    }
    let model_name = args
        .file
        .file_stem()
        .map_or_else(|| "model".to_string(), |s| s.to_string_lossy().into_owned());
    let stage = |source: &str| {
        let options = lagc::emit::EmitOptions {
            model_name: model_name.clone(),
            source_hash: crate::cli::source_hash(source),
            runtime_path: "../../runtime".to_string(),
            package_key: None,
        };
        lagc::compile_fmu(source, &options, "../../fmu")
    };
    let fmu = match super::compile(&args.file, stage, |fmu| fmu) {
        Ok(fmu) => fmu,
        Err(status) => return status,
    };
    let base = cache.join("fmu").join(lagc::emit::runtime_version());
    let dir = base.join("crates").join(&fmu.generated.package);
    let written = crate::cli::write_crate(&fmu.generated, &dir)
        .and_then(|()| crate::cli::write_runtime(&base.join("runtime")))
        .and_then(|()| write_library(&base.join("fmu")));
    if let Err(error) = written {
        eprintln!("error: cannot write under `{}`: {error}", base.display());
        return ExitCode::from(EXIT_USAGE);
    }
    let target = base.join("target");
    match crate::cli::cargo::cargo_build(&dir, &target) {
        Ok(build) if build.status.success() => {}
        Ok(build) => {
            eprintln!("error: {}", crate::cli::cargo::explain(&build.tail, &cache));
            return ExitCode::FAILURE;
        }
        Err(error) => {
            eprintln!("error: cannot run cargo: {error}");
            return ExitCode::FAILURE;
        }
    }
    let library = target
        .join("release")
        .join(format!("lib{}.so", fmu.model_identifier));
    let bytes = match std::fs::read(&library) {
        Ok(bytes) => bytes,
        Err(error) => {
            eprintln!("error: cannot read `{}`: {error}", library.display());
            return ExitCode::FAILURE;
        }
    };
    let so = format!("binaries/linux64/{}.so", fmu.model_identifier);
    let archive = crate::cli::zip::stored(&[
        ("modelDescription.xml", fmu.model_description.as_bytes()),
        (&so, &bytes),
    ]);
    let written = archive
        .map_err(|e| e.to_string())
        .and_then(|archive| std::fs::write(&args.output, archive).map_err(|e| e.to_string()));
    match written {
        Ok(()) => {
            eprintln!(
                "wrote FMU `{}` (FMI 2.0 co-simulation, {}) to {}",
                fmu.model_identifier,
                so,
                args.output.display()
            );
            ExitCode::SUCCESS
        }
        Err(error) => {
            eprintln!("error: cannot write `{}`: {error}", args.output.display());
            ExitCode::from(EXIT_USAGE)
        }
    }
}

/// Writes the lagc-fmu library's sources under `dir`.
fn write_library(dir: &Path) -> std::io::Result<()> {
    for (path, contents) in lagc::emit::fmu_library_files() {
        crate::cli::cache::write_if_changed(&dir.join(path), contents.as_bytes())?;
    }
    Ok(())
}
