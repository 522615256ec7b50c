//! Every example's run, to the bit: the whole CSV on stdout (as a hash)
//! and the summary's figures (every `--summary json` field but the wall
//! time), by both methods, as a snapshot. Recorded before the runtime's
//! driver became a steppable `Integration` (issue 25), so that the
//! renovation is proven not to change a single step or sample; any later
//! change of the numerics shows here too, and is accepted by reviewing the
//! snapshot. The binaries are the ones `generated.rs` builds (one shared
//! target directory), so this costs only the runs.

use crate::generated::build_file;
use std::process::Command;

/// FNV-1a, 64 bits: a stable hash (std's `DefaultHasher` may change
/// between Rust releases).
fn fnv1a(bytes: &[u8]) -> u64 {
    bytes.iter().fold(0xcbf2_9ce4_8422_2325, |h, &b| {
        (h ^ u64::from(b)).wrapping_mul(0x0100_0000_01b3)
    })
}

/// The summary's JSON line without its wall time.
fn figures(stderr: &str) -> String {
    let line = stderr
        .lines()
        .find(|l| l.starts_with("{\"method\"") || l.starts_with("{\"failed\""))
        .unwrap_or("(no summary)");
    line.split(',')
        .filter(|field| !field.starts_with("\"wall_time_s\""))
        .collect::<Vec<_>>()
        .join(",")
}

/// The runs of an example: its `field|direct within` lines as stated, else
/// (models without `exact` lines) both methods at the binary's defaults.
fn runs_of(path: &std::path::Path) -> Vec<Vec<String>> {
    let stated: Vec<Vec<String>> = crate::expect::expectations_of(path)
        .into_iter()
        .filter_map(|e| match e {
            crate::expect::Expectation::Within { run, .. } => Some(run.args()),
            _ => None,
        })
        .collect();
    if !stated.is_empty() {
        return stated;
    }
    ["field", "direct"]
        .iter()
        .map(|m| vec!["--method".to_string(), m.to_string()])
        .collect()
}

#[test]
fn every_example_runs_bit_identically_to_its_snapshot() {
    let mut report = String::new();
    for path in crate::expect::lag_files("examples") {
        let name = path.file_stem().unwrap().to_string_lossy().into_owned();
        let binary = build_file(&path);
        for mut args in runs_of(&path) {
            args.extend(["--summary".to_string(), "json".to_string()]);
            let output = Command::new(&binary).args(&args).output().unwrap();
            let stderr = String::from_utf8_lossy(&output.stderr);
            let rows = output.stdout.iter().filter(|&&b| b == b'\n').count();
            report.push_str(&format!(
                "{name} {}: exit {:?}, {rows} lines, fnv {:016x}\n  {}\n",
                args[..args.len() - 2].join(" "),
                output.status.code(),
                fnv1a(&output.stdout),
                figures(&stderr),
            ));
        }
    }
    insta::assert_snapshot!(report);
}
