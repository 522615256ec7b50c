//! `lagc report`: every method at a ladder of tolerances, error against
//! run time, as a table, a plot and the data.

use super::run::build_cached;
use super::{generate_cached, EXIT_USAGE};
use crate::cli::args::ReportArgs;
use std::io::IsTerminal;
use std::process::ExitCode;

pub(crate) fn report(args: &ReportArgs) -> ExitCode {
    let tolerances = match &args.tolerances {
        None => lagc::report::default_tolerances(),
        Some(text) => match lagc::report::parse_tolerances(text) {
            Ok(tolerances) => tolerances,
            Err(message) => {
                eprintln!("error: `--tolerances`: {message}");
                return ExitCode::from(EXIT_USAGE);
            }
        },
    };
    if args.runs == 0 {
        eprintln!("error: `--runs` must be at least 1");
        return ExitCode::from(EXIT_USAGE);
    }
    let generated = match generate_cached(&args.file) {
        Ok((generated, notes)) => {
            eprint!("{notes}");
            generated
        }
        Err(status) => return status,
    };
    let binary = match build_cached(&generated, &args.file) {
        Ok(binary) => binary,
        Err(status) => return status,
    };
    let mut common_args = Vec::new();
    for param in &args.params {
        common_args.extend(["--param".to_string(), param.clone()]);
    }
    common_args.extend(["--samples".to_string(), args.samples.to_string()]);
    if args.no_global_error {
        common_args.push("--no-global-error".to_string());
    }
    let model = args
        .file
        .file_name()
        .map_or_else(|| "model".to_string(), |s| s.to_string_lossy().into_owned());
    let plan = crate::cli::report::Plan {
        binary: &binary,
        model: model.clone(),
        tolerances,
        runs: args.runs,
        common_args,
    };
    let measured = match crate::cli::report::measure(&plan, std::io::stderr().is_terminal()) {
        Ok(measured) => measured,
        Err(message) => {
            eprintln!("error: {message}");
            return ExitCode::from(EXIT_USAGE);
        }
    };
    let svg = match lagc::report::work_precision_svg(&measured) {
        Ok(svg) => svg,
        Err(message) => {
            eprintln!("error: cannot draw the plot: {message}");
            return ExitCode::FAILURE;
        }
    };
    let stem = args
        .file
        .file_stem()
        .map_or_else(|| "model".to_string(), |s| s.to_string_lossy().into_owned());
    let svg_path = args.out.join(format!("{stem}.work-precision.svg"));
    let csv_path = args.out.join(format!("{stem}.work-precision.csv"));
    let written = std::fs::create_dir_all(&args.out)
        .and_then(|()| std::fs::write(&svg_path, svg))
        .and_then(|()| std::fs::write(&csv_path, lagc::report::data_csv(&measured)));
    if let Err(error) = written {
        eprintln!("error: cannot write to `{}`: {error}", args.out.display());
        return ExitCode::from(EXIT_USAGE);
    }
    print!("{}", lagc::report::table(&measured));
    println!("work-precision plot: {}", svg_path.display());
    println!("data: {}", csv_path.display());
    ExitCode::SUCCESS
}
