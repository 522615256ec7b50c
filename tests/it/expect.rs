//! Tests as data: the `// expect: …` header of a `.lag` file, parsed, and
//! the folders whose files carry one. `tests/README.md` documents the
//! format; each walker (errors, warnings, examples, stiff cases, run-time
//! failures, check ≡ build) reads its files' expectations from here, so
//! adding a test is adding a file. A file without a header, with a
//! malformed line, or with an `expect:` line outside its header fails.

use lagc::diagnostic::{Diagnostic, Severity};
use std::path::{Path, PathBuf};

/// One `// expect: …` line.
#[derive(Debug, Clone, PartialEq)]
pub enum Expectation {
    /// `check ok`: `lagc check` accepts the model.
    CheckOk,
    /// `error E0007 at 3:5`, `warning W0001 at 5:12`, `note N0001 at 9:1`
    /// (the position of the primary label; none when it has none).
    Diagnostic {
        severity: Severity,
        code: String,
        at: Option<(usize, usize)>,
    },
    /// `field within 1e-8 at rtol 1e-10`: the generated binary's run
    /// exits 0 and its largest error against the model's `exact` lines
    /// is at most the tolerance.
    Within { run: Run, tol: f64 },
    /// `outcome RUN: RESULT`: a stiff or extreme case's one allowed result.
    Outcome { run: Run, result: RunResult },
    /// `runtime failure RUN: RESULT`: a model made to fail at run time.
    RuntimeFailure { run: Run, result: RunResult },
}

/// How a generated binary is run: `field`/`direct`, an optional
/// integrator, tolerances, extra flags.
#[derive(Debug, Clone, PartialEq)]
pub struct Run {
    pub method: String,
    pub integrator: Option<String>,
    pub rtol: Option<String>,
    pub atol: Option<String>,
    pub flags: Vec<String>,
}

impl Run {
    /// The binary's command-line arguments.
    pub fn args(&self) -> Vec<String> {
        let mut args = vec!["--method".to_string(), self.method.clone()];
        if let Some(i) = &self.integrator {
            args.extend(["--integrator".to_string(), i.clone()]);
        }
        if let Some(r) = &self.rtol {
            args.extend(["--rtol".to_string(), r.clone()]);
        }
        if let Some(a) = &self.atol {
            args.extend(["--atol".to_string(), a.clone()]);
        }
        args.extend(self.flags.iter().cloned());
        args
    }
}

/// What a run must do.
#[derive(Debug, Clone, PartialEq)]
pub enum RunResult {
    /// `finishes within TOL [in at most N steps]`: exit 0, the error
    /// against the exact solution at most TOL (and the accepted steps at
    /// most N).
    Finishes { tol: f64, steps: Option<usize> },
    /// `exit N at t T ± W naming "a" [or "b" …]`: the exit status N, the
    /// failure's time (`error: at t = …`) within W of T, stderr holding
    /// one of the texts.
    Stops {
        exit: i32,
        time: f64,
        within: f64,
        naming: Vec<String>,
    },
}

/// The file's expectations: every `// expect:` line of its header (the
/// leading run of `//` comment lines). `Err` for a file without one, with
/// a malformed line, or with an `expect:` line below its header.
pub fn parse_header(text: &str) -> Result<Vec<Expectation>, String> {
    let mut expectations = Vec::new();
    let mut in_header = true;
    for (i, line) in text.lines().enumerate() {
        let trimmed = line.trim_end();
        if in_header && !trimmed.starts_with("//") {
            in_header = false;
        }
        let Some(rest) = trimmed.trim_start().strip_prefix("// expect:") else {
            if trimmed.contains("expect:") && trimmed.trim_start().starts_with("//") {
                return Err(format!(
                    "line {}: `expect:` must follow `// ` exactly",
                    i + 1
                ));
            }
            continue;
        };
        if !in_header {
            return Err(format!(
                "line {}: an `// expect:` line below the header comment",
                i + 1
            ));
        }
        let e = parse_line(rest.trim()).map_err(|e| format!("line {}: {e}", i + 1))?;
        expectations.push(e);
    }
    if expectations.is_empty() {
        return Err("no `// expect:` line in the header comment".to_string());
    }
    Ok(expectations)
}

/// [`parse_header`] of the file at `path`, panicking with the reason.
pub fn expectations_of(path: &Path) -> Vec<Expectation> {
    let bytes = std::fs::read(path).unwrap_or_else(|e| panic!("{}: {e}", path.display()));
    parse_header(&String::from_utf8_lossy(&bytes))
        .unwrap_or_else(|e| panic!("{}: malformed expectations: {e}", path.display()))
}

fn parse_line(line: &str) -> Result<Expectation, String> {
    let words = tokens(line)?;
    let w: Vec<&str> = words.iter().map(String::as_str).collect();
    match w.as_slice() {
        ["check", "ok"] => Ok(Expectation::CheckOk),
        [severity @ ("error" | "warning" | "note"), code, rest @ ..] => {
            let severity = match *severity {
                "error" => Severity::Error,
                "warning" => Severity::Warning,
                _ => Severity::Note,
            };
            let prefix = match severity {
                Severity::Error => 'E',
                Severity::Warning => 'W',
                Severity::Note => 'N',
            };
            if !(code.len() == 5
                && code.starts_with(prefix)
                && code[1..].bytes().all(|b| b.is_ascii_digit()))
            {
                return Err(format!("`{code}` is not a {prefix}NNNN code"));
            }
            let at = match rest {
                [] => None,
                ["at", position] => Some(position_of(position)?),
                _ => return Err(format!("expected `at LINE:COLUMN`, found {rest:?}")),
            };
            Ok(Expectation::Diagnostic {
                severity,
                code: code.to_string(),
                at,
            })
        }
        ["outcome", rest @ ..] => {
            let (run, result) = run_and_result(rest)?;
            Ok(Expectation::Outcome { run, result })
        }
        ["runtime", "failure", rest @ ..] => {
            let (run, result) = run_and_result(rest)?;
            Ok(Expectation::RuntimeFailure { run, result })
        }
        [method @ ("field" | "direct"), ..] => {
            let Some(within) = w.iter().position(|&x| x == "within") else {
                return Err(format!("`{method} …` needs `within TOL`"));
            };
            let tol = number(w.get(within + 1).copied())?;
            let mut run_words: Vec<&str> = w[..within].to_vec();
            run_words.extend(&w[within + 2..]);
            let run = run_of(&run_words)?;
            // Flags only after `with` (`… with --samples 191`).
            if !run.flags.is_empty() && !run_words.contains(&"with") {
                return Err(format!("unexpected words {:?}", run.flags));
            }
            Ok(Expectation::Within { run, tol })
        }
        _ => Err(format!("unknown expectation `{line}`")),
    }
}

/// Words, a `"…"` string one word (quotes kept), and `:` its own word.
fn tokens(line: &str) -> Result<Vec<String>, String> {
    let chars: Vec<char> = line.chars().collect();
    // A `:` between digits belongs to a position (`3:5`).
    let separator = |i: usize| {
        chars[i] == ':'
            && !(i > 0
                && chars[i - 1].is_ascii_digit()
                && chars.get(i + 1).is_some_and(char::is_ascii_digit))
    };
    let mut words = Vec::new();
    let mut i = 0;
    while i < chars.len() {
        if chars[i].is_whitespace() {
            i += 1;
        } else if chars[i] == '"' {
            let close = chars[i + 1..]
                .iter()
                .position(|&c| c == '"')
                .ok_or("an unclosed `\"`")?;
            let text: String = chars[i + 1..i + 1 + close].iter().collect();
            words.push(format!("\"{text}"));
            i += close + 2;
        } else if separator(i) {
            words.push(":".to_string());
            i += 1;
        } else {
            let start = i;
            while i < chars.len() && !chars[i].is_whitespace() && chars[i] != '"' && !separator(i) {
                i += 1;
            }
            words.push(chars[start..i].iter().collect());
        }
    }
    Ok(words)
}

fn position_of(word: &str) -> Result<(usize, usize), String> {
    let (l, c) = word
        .split_once(':')
        .ok_or_else(|| format!("`{word}` is not LINE:COLUMN"))?;
    match (l.parse(), c.parse()) {
        (Ok(l), Ok(c)) if l > 0 && c > 0 => Ok((l, c)),
        _ => Err(format!("`{word}` is not LINE:COLUMN")),
    }
}

fn number(word: Option<&str>) -> Result<f64, String> {
    let word = word.ok_or("a number is missing")?;
    match word.parse::<f64>() {
        Ok(x) if x.is_finite() && x >= 0.0 => Ok(x),
        _ => Err(format!("`{word}` is not a number")),
    }
}

/// `field|direct [explicit|stiff] [at rtol R [atol A]] [with FLAG …]`.
fn run_of(words: &[&str]) -> Result<Run, String> {
    let (method, mut rest) = match words {
        [m @ ("field" | "direct"), rest @ ..] => (m.to_string(), rest),
        _ => return Err(format!("a run starts with `field` or `direct`: {words:?}")),
    };
    let mut integrator = None;
    if let [i @ ("explicit" | "stiff"), tail @ ..] = rest {
        integrator = Some(i.to_string());
        rest = tail;
    }
    let (mut rtol, mut atol) = (None, None);
    if let ["at", "rtol", r, tail @ ..] = rest {
        number(Some(r))?;
        rtol = Some(r.to_string());
        rest = tail;
        if let ["atol", a, tail @ ..] = rest {
            number(Some(a))?;
            atol = Some(a.to_string());
            rest = tail;
        }
    }
    let flags = match rest {
        [] => Vec::new(),
        ["with", flags @ ..] if !flags.is_empty() => flags.iter().map(|f| f.to_string()).collect(),
        _ => rest.iter().map(|f| f.to_string()).collect(),
    };
    Ok(Run {
        method,
        integrator,
        rtol,
        atol,
        flags,
    })
}

/// `RUN : RESULT`.
fn run_and_result(words: &[&str]) -> Result<(Run, RunResult), String> {
    let colon = words
        .iter()
        .position(|&w| w == ":")
        .ok_or("a run needs `: RESULT`")?;
    let run = run_of(&words[..colon])?;
    if run.flags.first().is_some_and(|f| !f.starts_with("--")) {
        return Err(format!("unexpected words {:?}", run.flags));
    }
    let result = match &words[colon + 1..] {
        ["finishes", "within", tol, rest @ ..] => {
            let steps = match rest {
                [] => None,
                ["in", "at", "most", n, "steps"] => {
                    Some(n.parse().map_err(|_| format!("`{n}` is not a count"))?)
                }
                _ => return Err(format!("unexpected words {rest:?}")),
            };
            RunResult::Finishes {
                tol: number(Some(tol))?,
                steps,
            }
        }
        ["stops", "with", rest @ ..] | rest @ ["exit", ..] => match rest {
            ["exit", n, "at", "t", time, "±", within, "naming", names @ ..] => {
                let mut naming = Vec::new();
                for (i, name) in names.iter().enumerate() {
                    match (i % 2, name.strip_prefix('"')) {
                        (0, Some(text)) if !text.is_empty() => naming.push(text.to_string()),
                        (1, None) if *name == "or" => {}
                        _ => return Err(format!("expected `\"text\" [or \"text\" …]`: {names:?}")),
                    }
                }
                if naming.is_empty() || names.len() % 2 == 0 {
                    return Err(format!("expected `\"text\" [or \"text\" …]`: {names:?}"));
                }
                let time: f64 = time
                    .parse()
                    .map_err(|_| format!("`{time}` is not a time"))?;
                RunResult::Stops {
                    exit: n
                        .parse()
                        .map_err(|_| format!("`{n}` is not an exit status"))?,
                    time,
                    within: number(Some(within))?,
                    naming,
                }
            }
            _ => {
                return Err(format!(
                    "expected `exit N at t T ± W naming \"…\"`: {rest:?}"
                ))
            }
        },
        other => return Err(format!("unknown result {other:?}")),
    };
    Ok((run, result))
}

/// The `.lag` files of a folder under the repository root, sorted.
pub fn lag_files(dir: &str) -> Vec<PathBuf> {
    let mut files: Vec<PathBuf> = std::fs::read_dir(crate::root().join(dir))
        .unwrap_or_else(|e| panic!("{dir}: {e}"))
        .map(|e| e.unwrap().path())
        .filter(|p| p.extension().is_some_and(|e| e == "lag"))
        .collect();
    files.sort();
    files
}

/// Folders of models that `lagc check` accepts: every file states
/// `check ok` (and its warnings and notes).
pub const ACCEPTED: &[&str] = &[
    "examples",
    "tests/data/v2",
    "tests/data/mass_law_forms",
    "tests/data/runtime_failures",
    "tests/data/warnings",
    "tests/data/textbook",
    "tests/data/textbook_constraints",
    "tests/data/coupled_nonlinear",
    "tests/data/textbook_long",
    "tests/data/textbook_rolling",
    "tests/data/textbook_motion",
    "tests/data/textbook_loops",
    "tests/data/candidate_resets",
    "tests/data/raised_estimates",
    "tests/data",
];

/// Folders of models that `lagc check` refuses.
pub const REFUSED: &[&str] = &["tests/data/errors"];

/// A diagnostic as a header states it: severity, code, position.
pub type Stated = (Severity, String, Option<(usize, usize)>);

/// The header's diagnostics, sorted.
pub fn stated(expectations: &[Expectation]) -> Vec<Stated> {
    let mut out: Vec<Stated> = expectations
        .iter()
        .filter_map(|e| match e {
            Expectation::Diagnostic { severity, code, at } => Some((*severity, code.clone(), *at)),
            _ => None,
        })
        .collect();
    out.sort();
    out
}

/// The diagnostics as a header would state them (line and column of the
/// primary label, 1-based, columns in characters as rendered), sorted.
pub fn as_stated(diagnostics: &[Diagnostic], source: &str) -> Vec<Stated> {
    let mut out: Vec<Stated> = diagnostics
        .iter()
        .map(|d| {
            let at = d.labels.iter().find(|l| l.primary).map(|l| {
                let start = l.span.start.min(source.len());
                let before = &source[..start];
                let line = before.matches('\n').count() + 1;
                let line_start = before.rfind('\n').map_or(0, |i| i + 1);
                (line, source[line_start..start].chars().count() + 1)
            });
            (d.severity, d.code.to_string(), at)
        })
        .collect();
    out.sort();
    out
}

/// `error E0002 at 3:5` lines for a diagnostic list (for a failure message
/// that shows what to write).
pub fn header_lines(stated: &[Stated]) -> String {
    stated
        .iter()
        .map(|(s, code, at)| {
            let kind = match s {
                Severity::Error => "error",
                Severity::Warning => "warning",
                Severity::Note => "note",
            };
            match at {
                Some((l, c)) => format!("// expect: {kind} {code} at {l}:{c}\n"),
                None => format!("// expect: {kind} {code}\n"),
            }
        })
        .collect()
}

#[test]
fn the_header_format_parses_and_refuses() {
    let ok = "// expect: error E0007 at 3:5\n// expect: warning W0001 at 4:12\n// what is wrong\ncoord x;\n";
    assert_eq!(parse_header(ok).unwrap().len(), 2);
    let run = "// expect: direct stiff within 1e-8 at rtol 1e-10 atol 1e-12\n\
               // expect: outcome field at rtol 1e-10: stops with exit 3 at t 1 ± 1e-4 naming \"a\" or \"b\"\n\
               // expect: runtime failure field explicit with --no-reanchor: exit 3 at t 0.45 ± 0.03 naming \"c\"\n\
               // expect: outcome direct stiff at rtol 1e-10 atol 1e-12 with --samples 2: finishes within 1e-7 in at most 250000 steps\n";
    let e = parse_header(run).unwrap();
    assert_eq!(
        e[0],
        Expectation::Within {
            run: Run {
                method: "direct".into(),
                integrator: Some("stiff".into()),
                rtol: Some("1e-10".into()),
                atol: Some("1e-12".into()),
                flags: vec![],
            },
            tol: 1e-8
        }
    );
    let Expectation::Outcome { result, .. } = &e[1] else {
        panic!("{e:?}")
    };
    assert_eq!(
        result,
        &RunResult::Stops {
            exit: 3,
            time: 1.0,
            within: 1e-4,
            naming: vec!["a".into(), "b".into()]
        }
    );
    let Expectation::RuntimeFailure { run, .. } = &e[2] else {
        panic!("{e:?}")
    };
    assert_eq!(
        run.args(),
        [
            "--method",
            "field",
            "--integrator",
            "explicit",
            "--no-reanchor"
        ]
    );
    let Expectation::Outcome { run, result } = &e[3] else {
        panic!("{e:?}")
    };
    assert_eq!(run.flags, ["--samples", "2"]);
    assert_eq!(
        result,
        &RunResult::Finishes {
            tol: 1e-7,
            steps: Some(250000)
        }
    );
    for bad in [
        "coord x;\n",
        "// no header\ncoord x;\n",
        "// expect: error E7 at 3:5\n",
        "// expect: error E0007 at 3\n",
        "// expect: warning E0007 at 3:5\n",
        "// expect: check fine\n",
        "// expect: field within\n",
        "// expect: field within 1e-8 at rtol\n",
        "// expect: field within x\n",
        "// expect: outcome field at rtol 1e-10 finishes within 1e-6\n",
        "// expect: outcome field: exit 3 at t 1 ± 1 naming a\n",
        "// expect: outcome field: exit 3 at t 1 ± 1 naming \"a\" \"b\"\n",
        "// expect: runtime failure field: exit 3 naming \"a\"\n",
        "// expect: check ok\ncoord x;\n// expect: check ok\n",
        "//expect: check ok\n",
    ] {
        assert!(parse_header(bad).is_err(), "{bad:?} parses");
    }
}

/// What `lagc check` reports on a file's bytes, as the CLI does: the
/// decoded text, and the model or every diagnostic (the text's warnings
/// included, sorted); on success the warnings are [`lagc::source_warnings`].
pub fn check_diagnostics(
    bytes: &[u8],
) -> (String, Result<lagc::check::model::Model, Vec<Diagnostic>>) {
    lagc::on_big_stack(|| {
        let (source, checked) = lagc::check_and_derive_bytes(bytes);
        let warnings = lagc::source_warnings(&source);
        let result = match checked {
            Ok((model, _)) => Ok(model),
            Err(mut diagnostics) => {
                diagnostics.extend(warnings);
                lagc::diagnostic::sort(&mut diagnostics);
                Err(diagnostics)
            }
        };
        (source.into_owned(), result)
    })
}

/// Runs `binary` as `run` states and checks `result`; `Ok` holds the
/// run's label and stderr, `Err` says what differs.
pub fn run_as_stated(
    binary: &Path,
    name: &str,
    run: &Run,
    result: &RunResult,
) -> Result<(String, String), String> {
    let args = run.args();
    let output = std::process::Command::new(binary)
        .args(&args)
        .output()
        .unwrap();
    let stderr = String::from_utf8_lossy(&output.stderr).into_owned();
    let label = format!("{name} {}", args.join(" "));
    match result {
        RunResult::Finishes { tol, steps } => {
            if output.status.code() != Some(0) {
                return Err(format!(
                    "{label}: exit {:?}, not 0\n{stderr}",
                    output.status
                ));
            }
            let error: f64 = stderr
                .lines()
                .find_map(|l| l.strip_prefix("largest error against the exact solution: "))
                .and_then(|v| v.trim().parse().ok())
                .ok_or_else(|| format!("{label}: no exact error in\n{stderr}"))?;
            if error.is_nan() || error > *tol {
                return Err(format!("{label}: exit 0 with error {error:e} > {tol:e}"));
            }
            if let Some(budget) = steps {
                let taken: usize = stderr
                    .split("steps: ")
                    .nth(1)
                    .and_then(|rest| rest.split_whitespace().next())
                    .and_then(|n| n.parse().ok())
                    .ok_or_else(|| format!("{label}: no step count in\n{stderr}"))?;
                if taken > *budget {
                    return Err(format!("{label}: {taken} steps > {budget}"));
                }
            }
        }
        RunResult::Stops {
            exit,
            time,
            within,
            naming,
        } => {
            if output.status.code() != Some(*exit) {
                return Err(format!(
                    "{label}: exit {:?}, not {exit}\n{stderr}",
                    output.status
                ));
            }
            let reported = stderr
                .lines()
                .find_map(|l| l.strip_prefix("error: at t = "))
                .and_then(|rest| rest.split(':').next())
                .and_then(|t| t.trim().parse::<f64>().ok());
            match reported {
                Some(t) if (t - time).abs() <= *within => {}
                other => {
                    return Err(format!(
                        "{label}: failure time {other:?}, not {time} ± {within}\n{stderr}"
                    ))
                }
            }
            if !naming.iter().any(|q| stderr.contains(q.as_str())) {
                return Err(format!("{label}: none of {naming:?} in\n{stderr}"));
            }
        }
    }
    Ok((label, stderr))
}

/// Every `.lag` file under `tests/data/` lies in a folder a walker reads:
/// a new folder would otherwise hold files nothing tests.
#[test]
fn every_test_model_is_in_a_walked_folder() {
    fn walk(dir: &Path, out: &mut Vec<PathBuf>) {
        for entry in std::fs::read_dir(dir).unwrap() {
            let path = entry.unwrap().path();
            if path.is_dir() {
                walk(&path, out);
            } else if path.extension().is_some_and(|e| e == "lag") {
                out.push(path);
            }
        }
    }
    let root = crate::root();
    let mut files = Vec::new();
    walk(&root.join("tests/data"), &mut files);
    walk(&root.join("examples"), &mut files);
    for path in files {
        let dir = path.parent().unwrap().strip_prefix(&root).unwrap();
        let dir = dir.to_string_lossy().replace('\\', "/");
        assert!(
            ACCEPTED.iter().chain(REFUSED).any(|d| *d == dir),
            "{}: its folder is walked by no test (expect::ACCEPTED, expect::REFUSED)",
            path.display()
        );
    }
}
