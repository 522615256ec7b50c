//! The front end as one call: source → checked model or diagnostics.
//!
//! The CLI and the tests call these same functions, so the tests exercise
//! exactly what the CLI does.

use crate::check::{self, model::Model};
use crate::diagnostic::{codes, Diagnostic};
use crate::mechanics::Derivation;
use crate::span::Span;
use crate::syntax;
use std::borrow::Cow;
use std::sync::Mutex;

/// The stack the front end (and later recursive stages) runs on. Expression
/// depth is bounded by [`syntax::MAX_EXPR_DEPTH`]; this leaves a wide margin
/// for unoptimised builds. Only touched pages are committed.
pub const STACK_SIZE: usize = 256 * 1024 * 1024;

/// Parses and checks a `.lag` source text.
pub fn frontend(source: &str) -> Result<Model, Vec<Diagnostic>> {
    let ast = syntax::parse(source)?;
    let mut model = check::check(&ast)?;
    for constraint in &mut model.constraints {
        constraint.text = statement_text(source, constraint.span, "constraint");
    }
    Ok(model)
}

/// A statement's text as written, for run-time messages: on one line,
/// without its keyword, its `;`, comments or runs of white space.
pub fn statement_text(source: &str, span: Span, keyword: &str) -> String {
    let Some(text) = source.get(span.range()) else {
        return String::new();
    };
    let words: Vec<&str> = text
        .lines()
        .map(|line| line.split("//").next().unwrap_or(""))
        .flat_map(str::split_whitespace)
        .collect();
    let joined = words.join(" ");
    let joined = joined.strip_prefix(keyword).unwrap_or(&joined).trim();
    joined
        .strip_suffix(';')
        .unwrap_or(joined)
        .trim()
        .to_string()
}

/// The front end, the derivation and the kernel: every diagnostic a model
/// can have before code generation prints (`lagc check` reports exactly
/// these, and `lagc build` no others). Some checks
/// need the symbolic stage: an initial value that violates a constraint, an
/// identically singular mass matrix, equations (4) that fail the
/// cross-check ([`crate::mechanics::derive_checked`], as every path).
pub fn check_and_derive(source: &str) -> Checked {
    let model = frontend(source)?;
    let (derivation, _) = crate::mechanics::derive_checked(&model)?;
    // What the kernel can still reject (an initial value against a
    // constraint, an output beyond the state, …): check ≡ build.
    crate::pipeline::kernel_of(&model, derivation.clone())?;
    Ok((model, derivation))
}

/// [`check_and_derive`] for a caller that needs only the checked model
/// (`lagc check`): the derivation goes on into the kernel without the
/// copy that returning it takes. The kernel is returned so that a caller
/// about to exit may leave it unfreed (a large model's arena holds
/// millions of nodes, and freeing them one by one is a visible share of
/// `lagc check`).
pub fn check_through_kernel(
    source: &str,
) -> Result<(Model, crate::kernel::Kernel), Vec<Diagnostic>> {
    let model = frontend(source)?;
    let (derivation, _) = crate::mechanics::derive_checked(&model)?;
    let (kernel, _) = crate::pipeline::kernel_of(&model, derivation)?;
    Ok((model, kernel))
}

/// Warnings about the text that do not stop a model, reported by every
/// command alike: literals that underflow ([`literal_warnings`], W0001),
/// and `atan2` in a position constraint (W0002,
/// [`check::atan2_cut`]), on a model that parses.
pub fn source_warnings(source: &str) -> Vec<Diagnostic> {
    let mut warnings = literal_warnings(source);
    // A model without the name `atan2` in its text has no `atan2` call, and
    // parsing it again (the front end parses it too) is a visible share of
    // `lagc check` on a large model.
    if !source.contains("atan2") {
        return warnings_sorted(warnings);
    }
    if let Ok(ast) = syntax::parse(source) {
        warnings.extend(check::atan2_cut::atan2_cut_warnings(&ast));
    }
    warnings_sorted(warnings)
}

fn warnings_sorted(mut warnings: Vec<Diagnostic>) -> Vec<Diagnostic> {
    crate::diagnostic::sort(&mut warnings);
    warnings
}

/// A number literal such as `1e-400`, non-zero as written but below the
/// smallest positive f64, which is read as 0 (W0001). A lexical scan with
/// the grammar's `number` rule (comments and names skipped), independent
/// of the parse.
pub fn literal_warnings(source: &str) -> Vec<Diagnostic> {
    let bytes = source.as_bytes();
    let digits = |mut i: usize| {
        while i < bytes.len() && bytes[i].is_ascii_digit() {
            i += 1;
        }
        i
    };
    let mut warnings = Vec::new();
    let mut i = 0;
    while i < bytes.len() {
        let b = bytes[i];
        if b == b'/' && bytes.get(i + 1) == Some(&b'/') {
            while i < bytes.len() && !matches!(bytes[i], b'\n' | b'\r') {
                i += 1;
            }
        } else if b.is_ascii_alphabetic() || b == b'_' {
            while i < bytes.len() && (bytes[i].is_ascii_alphanumeric() || bytes[i] == b'_') {
                i += 1;
            }
        } else if b.is_ascii_digit() {
            // number = digit+ ("." digit+)? (e ("+"|"-")? digit+)?
            let start = i;
            i = digits(i);
            if bytes.get(i) == Some(&b'.') && bytes.get(i + 1).is_some_and(u8::is_ascii_digit) {
                i = digits(i + 1);
            }
            let mantissa_end = i;
            if matches!(bytes.get(i), Some(b'e' | b'E')) {
                let sign = usize::from(matches!(bytes.get(i + 1), Some(b'+' | b'-')));
                if bytes.get(i + 1 + sign).is_some_and(u8::is_ascii_digit) {
                    i = digits(i + 1 + sign);
                }
            }
            let text = &source[start..i];
            let nonzero = source[start..mantissa_end]
                .bytes()
                .any(|d| matches!(d, b'1'..=b'9'));
            if nonzero && text.parse::<f64>() == Ok(0.0) {
                warnings.push(
                    Diagnostic::warning(codes::LITERAL_UNDERFLOWS, "this literal underflows to 0")
                        .with_primary(
                            Span::new(start, i),
                            format!("`{text}` is read as 0"),
                        )
                        .with_note(format!(
                            "the smallest positive 64-bit float is about {:e}",
                            f64::from_bits(1)
                        ))
                        .with_help("write 0 if zero is meant, or choose units in which the value is not this small"),
                );
            }
        } else {
            i += 1;
        }
    }
    warnings
}

/// Decodes a file's bytes and runs [`frontend`]. Also returns the text to
/// render diagnostics against: the source itself (lone `\r` line ends read
/// as `\n`, byte for byte), or for invalid UTF-8 a lossy copy (each invalid sequence replaced by U+FFFD) in which the
/// diagnostic's span marks the first replacement character.
pub fn frontend_bytes(bytes: &[u8]) -> (Cow<'_, str>, Result<Model, Vec<Diagnostic>>) {
    decode_then(bytes, frontend)
}

/// The checked model and its derivation, or every diagnostic.
pub type Checked = Result<(Model, Derivation), Vec<Diagnostic>>;

/// Decodes a file's bytes and runs [`check_and_derive`]; see [`frontend_bytes`].
pub fn check_and_derive_bytes(bytes: &[u8]) -> (Cow<'_, str>, Checked) {
    decode_then(bytes, check_and_derive)
}

/// Decodes a file's bytes and runs `stage` on the text; see [`frontend_bytes`].
pub fn decode_then<T>(
    bytes: &[u8],
    stage: impl FnOnce(&str) -> Result<T, Vec<Diagnostic>>,
) -> (Cow<'_, str>, Result<T, Vec<Diagnostic>>) {
    match std::str::from_utf8(bytes) {
        Ok(source) => {
            let source = lone_cr_as_newline(Cow::Borrowed(source));
            let result = stage(&source);
            (source, result)
        }
        Err(error) => {
            let offset = error.valid_up_to();
            let replacement = char::REPLACEMENT_CHARACTER.len_utf8();
            let diagnostic = Diagnostic::error(
                codes::INVALID_UTF8,
                format!("the file is not valid UTF-8: invalid byte at offset {offset}"),
            )
            .with_primary(
                Span::new(offset, offset + replacement),
                format!("byte {offset} is not UTF-8 (shown as \u{FFFD})"),
            )
            .with_help("save the file as UTF-8 text");
            let source = lone_cr_as_newline(String::from_utf8_lossy(bytes));
            (source, Err(vec![diagnostic]))
        }
    }
}

/// The text with every lone `\r` (old Mac line endings, not part of a
/// `\r\n`) replaced by `\n`, so that a CR-only file has its lines: for
/// line numbers in diagnostics (codespan counts `\n`) and for every check
/// that looks at line ends. The replacement is byte for byte, so spans into
/// the original text stay valid.
fn lone_cr_as_newline(source: Cow<'_, str>) -> Cow<'_, str> {
    let bytes = source.as_bytes();
    let lone = |i: usize| bytes[i] == b'\r' && bytes.get(i + 1) != Some(&b'\n');
    if !(0..bytes.len()).any(lone) {
        return source;
    }
    let mut text = String::with_capacity(source.len());
    for (i, c) in source.char_indices() {
        text.push(if lone(i) { '\n' } else { c });
    }
    Cow::Owned(text)
}

/// Runs `job` on a thread with a [`STACK_SIZE`] stack, and returns its
/// result. A panic in `job` is resumed in the caller. Should the thread not
/// start (no resources), `job` runs on the current thread instead.
pub fn on_big_stack<T: Send>(job: impl FnOnce() -> T + Send) -> T {
    let slot = Mutex::new(Some(job));
    let take = || slot.lock().ok().and_then(|mut job| job.take());
    let spawned = std::thread::scope(|scope| {
        let handle = std::thread::Builder::new()
            .name("lagc-frontend".into())
            .stack_size(STACK_SIZE)
            .spawn_scoped(scope, || take().map(|job| job()));
        match handle {
            Ok(handle) => match handle.join() {
                Ok(result) => result,
                Err(panic) => std::panic::resume_unwind(panic),
            },
            Err(_) => None,
        }
    });
    match spawned {
        Some(result) => result,
        None => match take() {
            Some(job) => job(),
            // Unreachable: the job ran exactly when the thread returned Some.
            None => unreachable!("the front-end job ran but returned nothing"),
        },
    }
}
