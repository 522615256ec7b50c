//! `lagc report`: the pure table/plot/parsing functions, and the command
//! end to end on small models with a short ladder.

use lagc::report::{
    atol_for, data_csv, default_tolerances, largest_difference, parse_csv, parse_summary,
    parse_tolerances, reference_for, table, work_precision_svg, Measurement, Method, Outcome,
    Report, RunSummary,
};
use std::process::Command;

fn summary(method: &str, seconds: f64) -> RunSummary {
    RunSummary {
        method: method.to_string(),
        steps: 12,
        rhs_evaluations: 150,
        wall_time_s: seconds,
        largest_condition: None,
        reanchorings: None,
        exact_error: None,
    }
}

/// Two tolerances for each method; RODAS4 fails at the tight one.
fn sample_report() -> Report {
    let mut measurements = Vec::new();
    for (i, method) in Method::ALL.into_iter().enumerate() {
        for (j, rtol) in [1e-4, 1e-8].into_iter().enumerate() {
            let outcome = if method == Method::Stiff && j == 1 {
                Outcome::Failed {
                    message: "at t = 1e0: the step size 1e-17 underflows".to_string(),
                }
            } else {
                Outcome::Solved {
                    summary: summary(method.label(), 1e-4 * (i + j + 1) as f64),
                    error: Some(rtol * 10.0),
                }
            };
            measurements.push(Measurement {
                method,
                rtol,
                atol: atol_for(rtol),
                outcome,
            });
        }
    }
    Report {
        model: "toy.lag".to_string(),
        error_basis: "the model's exact solution".to_string(),
        runs: 3,
        measurements,
    }
}

#[test]
fn table_has_a_row_per_run_and_failed_runs_with_their_message() {
    let text = table(&sample_report());
    let lines: Vec<&str> = text.lines().collect();
    assert_eq!(lines.len(), 2 + 6, "{text}");
    assert!(lines[0].starts_with("toy.lag: ") && lines[0].contains("smallest of 3 solves"));
    assert!(lines[1].starts_with("method"));
    // Tolerances print as typed, atol = rtol·1e-2 included.
    assert!(
        lines[2].starts_with("field") && lines[2].contains(" 1e-4   1e-6 "),
        "{}",
        lines[2]
    );
    assert!(
        lines[2].contains("0.1000") && lines[2].contains("1.00e-3"),
        "{}",
        lines[2]
    );
    assert!(lines[7].starts_with("direct RODAS4"), "{}", lines[7]);
    assert!(
        lines[7].contains("failed: at t = 1e0: the step size 1e-17 underflows"),
        "{}",
        lines[7]
    );
    let csv = data_csv(&sample_report());
    assert_eq!(csv.lines().count(), 7);
    assert!(csv.lines().last().unwrap().contains(",failed,\"at t = 1e0"));
}

#[test]
fn plot_has_one_polyline_per_method_that_solved() {
    let svg = work_precision_svg(&sample_report()).unwrap();
    assert!(svg.starts_with("<svg") && svg.trim_end().ends_with("</svg>"));
    for colour in ["#D62728", "#1F77B4", "#2CA02C"] {
        let lines = svg
            .lines()
            .filter(|l| l.contains("<polyline") && l.contains(&format!("stroke=\"{colour}\"")))
            .count();
        assert_eq!(lines, 1, "{colour}");
    }
    assert!(svg.contains("work-precision: toy.lag"));
    // Every method is in the legend, the one with no solution at all too.
    let mut report = sample_report();
    report.measurements.retain(|m| m.method != Method::Stiff);
    let svg = work_precision_svg(&report).unwrap();
    assert_eq!(svg.matches("stroke=\"#2CA02C\"").count(), 0);
    assert!(svg.contains("direct RODAS4 (failed)"));
}

#[test]
fn summary_lines_parse_and_failures_give_their_message() {
    let stderr = "some note\n{\"method\":\"field (DOP853)\",\"steps\":13,\"rejected_steps\":0,\
                  \"rhs_evaluations\":158,\"largest_condition\":4.4e2,\"reanchorings\":0,\
                  \"wall_time_s\":7.38e-5,\"runs\":5,\"exact_error\":null}\n";
    let parsed = parse_summary(stderr).unwrap();
    assert_eq!(parsed.method, "field (DOP853)");
    assert_eq!((parsed.steps, parsed.rhs_evaluations), (13, 158));
    assert_eq!(parsed.wall_time_s, 7.38e-5);
    assert_eq!(parsed.largest_condition, Some(440.0));
    assert_eq!(parsed.reanchorings, Some(0));
    assert_eq!(parsed.exact_error, None);
    let failed =
        "{\"failed\":true,\"message\":\"at t = 2e0: `q1'` is \\\"not\\\" finite\"}\nerror: …";
    assert_eq!(
        parse_summary(failed),
        Err("at t = 2e0: `q1'` is \"not\" finite".to_string())
    );
    assert!(parse_summary("no json here").is_err());
    assert!(parse_summary("{\"method\":\"x\",\"steps\":}").is_err());
}

#[test]
fn csv_difference_is_relative_to_the_reference_and_checks_the_times() {
    let a = parse_csv("t,x,x'\n0,1,2\n1,4,-300\n").unwrap();
    let b = parse_csv("t,x,x'\n0,1.5,2\n1,4,-303\n").unwrap();
    // |1 − 1.5| / 1.5 = 1/3; |−300 + 303| / 303 ≈ 0.0099.
    let d = largest_difference(&a, &b).unwrap();
    assert!((d - 1.0 / 3.0).abs() < 1e-15, "{d}");
    let shifted = parse_csv("t,x,x'\n0,1,2\n2,4,-300\n").unwrap();
    assert!(largest_difference(&a, &shifted).is_err());
    assert!(parse_csv("t,x\n0,1,2\n").is_err());
}

#[test]
fn ladder_and_references() {
    let ladder = default_tolerances();
    assert_eq!(ladder.len(), 10);
    assert_eq!((ladder[0], ladder[9]), (1e-3, 1e-12));
    assert_eq!(parse_tolerances("1e-4, 1e-8").unwrap(), vec![1e-4, 1e-8]);
    assert!(parse_tolerances("1e-4,2").is_err() && parse_tolerances("x").is_err());
    for method in Method::ALL {
        assert_ne!(reference_for(method), method);
    }
}

/// `lagc report` with the tests' own `lagc` cache (shared with `cli.rs`;
/// `generated.rs` writes crates of the same names with other contents).
fn lagc_report(model: &std::path::Path, out: &std::path::Path, tolerances: &str) -> String {
    let cache = crate::root().join("target/lagc-cache");
    let output = Command::new(env!("CARGO_BIN_EXE_lagc"))
        .arg("report")
        .arg(model)
        .args(["--tolerances", tolerances, "--runs", "1", "--out"])
        .arg(out)
        .env("LAGC_CACHE_DIR", &cache)
        .env("RUSTFLAGS", "-D warnings")
        .current_dir(crate::root())
        .output()
        .unwrap();
    let stdout = String::from_utf8(output.stdout).unwrap();
    assert!(
        output.status.success(),
        "{stdout}\n{}",
        String::from_utf8_lossy(&output.stderr)
    );
    stdout
}

/// The error column of a table row (after the 15-character method).
fn row_error(row: &str) -> f64 {
    let columns: Vec<&str> = row[15..].split_whitespace().collect();
    columns[3]
        .parse()
        .unwrap_or_else(|_| panic!("no error in {row}"))
}

fn out_dir(name: &str) -> std::path::PathBuf {
    let dir = crate::root().join("target/test-report").join(name);
    let _ = std::fs::remove_dir_all(&dir);
    dir
}

#[test]
fn report_on_an_example_with_exact_solution_writes_table_plot_and_data() {
    let out = out_dir("damped");
    let stdout = lagc_report(
        &crate::root().join("examples/damped_oscillator.lag"),
        &out,
        "1e-4,1e-8",
    );
    assert!(
        stdout.contains("truth = the model's exact solution"),
        "{stdout}"
    );
    let rows: Vec<&str> = stdout
        .lines()
        .filter(|l| l.starts_with("field") || l.starts_with("direct"))
        .collect();
    assert_eq!(rows.len(), 6, "{stdout}");
    // Each error is a number, and the tighter tolerance is more accurate.
    let error = |row: &str| -> f64 { row_error(row) };
    for pair in rows.chunks(2) {
        assert!(error(pair[1]) < error(pair[0]), "{stdout}");
    }
    let svg_path = out.join("damped_oscillator.work-precision.svg");
    assert!(stdout.contains(&format!("work-precision plot: {}", svg_path.display())));
    let svg = std::fs::read_to_string(&svg_path).unwrap();
    assert_eq!(
        svg.matches("<polyline fill=\"none\" opacity=\"1\" stroke=\"#D62728\"")
            .count(),
        1
    );
    let csv = std::fs::read_to_string(out.join("damped_oscillator.work-precision.csv")).unwrap();
    assert_eq!(csv.lines().count(), 7);
}

#[test]
fn report_without_exact_solution_measures_against_another_method() {
    let out = out_dir("no-exact");
    std::fs::create_dir_all(&out).unwrap();
    let model = out.join("report_oscillator.lag");
    std::fs::write(
        &model,
        "param w = 2;\ncoord x;\nlagrangian = x'^2 / 2 - w^2 * x^2 / 2;\n\
         initial x = 1, x' = 0;\ntime 0 .. 3;\n",
    )
    .unwrap();
    let stdout = lagc_report(&model, &out, "1e-5");
    assert!(
        stdout.contains("truth = a reference at rtol 1e-13"),
        "{stdout}"
    );
    for row in stdout
        .lines()
        .filter(|l| l.starts_with("field") || l.starts_with("direct"))
    {
        let error = row_error(row);
        assert!(error > 0.0 && error < 1e-3, "{row}");
    }
}
