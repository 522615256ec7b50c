//! The one diagnostic type of lagc, and its rendering at the edge.
//!
//! Every stage reports problems as [`Diagnostic`] values; nothing in the
//! pipeline prints. [`render`] turns them into rustc-style text with
//! codespan-reporting, and `main.rs` writes that text to stderr.

use crate::span::Span;
use codespan_reporting::diagnostic as cs;
use codespan_reporting::files::SimpleFile;
use codespan_reporting::term::{self, termcolor};

#[derive(Debug, Clone, Copy, PartialEq, Eq, PartialOrd, Ord)]
pub enum Severity {
    Error,
    Warning,
    Note,
}

/// A source location with a message; the primary label marks the mistake itself.
#[derive(Debug, Clone, PartialEq)]
pub struct Label {
    pub span: Span,
    pub message: String,
    pub primary: bool,
}

#[derive(Debug, Clone, PartialEq)]
pub struct Diagnostic {
    pub severity: Severity,
    /// A stable code such as `E0002`; see [`codes`].
    pub code: &'static str,
    pub message: String,
    pub labels: Vec<Label>,
    pub notes: Vec<String>,
    pub help: Option<String>,
}

impl Diagnostic {
    pub fn error(code: &'static str, message: impl Into<String>) -> Self {
        Diagnostic {
            severity: Severity::Error,
            code,
            message: message.into(),
            labels: Vec::new(),
            notes: Vec::new(),
            help: None,
        }
    }

    pub fn warning(code: &'static str, message: impl Into<String>) -> Self {
        Diagnostic {
            severity: Severity::Warning,
            ..Diagnostic::error(code, message)
        }
    }

    pub fn note_diagnostic(code: &'static str, message: impl Into<String>) -> Self {
        Diagnostic {
            severity: Severity::Note,
            ..Diagnostic::error(code, message)
        }
    }

    pub fn with_primary(mut self, span: Span, message: impl Into<String>) -> Self {
        self.labels.push(Label {
            span,
            message: message.into(),
            primary: true,
        });
        self
    }

    pub fn with_secondary(mut self, span: Span, message: impl Into<String>) -> Self {
        self.labels.push(Label {
            span,
            message: message.into(),
            primary: false,
        });
        self
    }

    pub fn with_note(mut self, note: impl Into<String>) -> Self {
        self.notes.push(note.into());
        self
    }

    pub fn with_help(mut self, help: impl Into<String>) -> Self {
        self.help = Some(help.into());
        self
    }

    pub fn is_error(&self) -> bool {
        self.severity == Severity::Error
    }

    /// The position used to sort diagnostics: the start of the primary label.
    pub fn position(&self) -> usize {
        self.labels
            .iter()
            .find(|l| l.primary)
            .or(self.labels.first())
            .map_or(usize::MAX, |l| l.span.start)
    }
}

/// Sorts diagnostics by source position (stable, so equal positions keep
/// the order in which the checks found them).
pub fn sort(diagnostics: &mut [Diagnostic]) {
    diagnostics.sort_by_key(Diagnostic::position);
}

/// Renders diagnostics as rustc-style text (`file:line:col`, code, labels,
/// notes, help). `color` selects ANSI colours; tests render without.
///
/// Control characters never reach the terminal raw: in the snippet each is
/// shown as its picture (`␀` for NUL, U+2400–U+2421; U+FFFD for the C1
/// controls) and a lone `\r` as a line end, labels moved to match; in the
/// messages, labels, notes and file name each is escaped (`\0`, `\u{1}`).
pub fn render(diagnostics: &[Diagnostic], file_name: &str, source: &str, color: bool) -> String {
    let shown = Shown::new(source);
    let file = SimpleFile::new(escape_controls(file_name), shown.text.as_str());
    let mut buffer = if color {
        termcolor::Buffer::ansi()
    } else {
        termcolor::Buffer::no_color()
    };
    let config = term::Config::default();
    for diagnostic in diagnostics {
        let cs_diagnostic = to_codespan(diagnostic, source.len(), &shown);
        // Writing into an in-memory buffer cannot fail for I/O reasons; a
        // failure here would be a span outside the file, which to_codespan clamps.
        let _ = term::emit_to_write_style(&mut buffer, &config, &file, &cs_diagnostic);
    }
    String::from_utf8_lossy(buffer.as_slice()).into_owned()
}

/// The source as a snippet shows it (see [`render`]), and where each
/// offset of the source went.
struct Shown {
    text: String,
    /// `(start in the source, bytes added up to and including this
    /// character)` for every character whose picture is longer than it.
    shifts: Vec<(usize, usize)>,
}

impl Shown {
    fn new(source: &str) -> Self {
        let bytes = source.as_bytes();
        let mut text = String::with_capacity(source.len());
        let mut shifts = Vec::new();
        let mut added = 0;
        for (i, c) in source.char_indices() {
            let picture = match c {
                '\n' | '\t' => c,
                '\r' if bytes.get(i + 1) == Some(&b'\n') => c,
                '\r' => '\n',
                '\u{0}'..='\u{1f}' => char::from_u32(0x2400 + c as u32).unwrap_or('\u{FFFD}'),
                '\u{7f}' => '\u{2421}',
                c if c.is_control() => '\u{FFFD}',
                c => c,
            };
            text.push(picture);
            if picture.len_utf8() > c.len_utf8() {
                added += picture.len_utf8() - c.len_utf8();
                shifts.push((i, added));
            }
        }
        Shown { text, shifts }
    }

    /// The offset in the shown text of `offset` in the source: after every
    /// picture of a character that starts before it.
    fn offset(&self, offset: usize) -> usize {
        match self.shifts.partition_point(|&(start, _)| start < offset) {
            0 => offset,
            n => offset + self.shifts[n - 1].1,
        }
    }
}

/// `text` with every control character but `\n` escaped as in Rust source
/// (`\0`, `\t`, `\r`, `\u{1b}`), so that quoted source text cannot act on
/// the terminal.
fn escape_controls(text: &str) -> std::borrow::Cow<'_, str> {
    if !text.chars().any(|c| c.is_control() && c != '\n') {
        return std::borrow::Cow::Borrowed(text);
    }
    let mut escaped = String::with_capacity(text.len() + 8);
    for c in text.chars() {
        match c {
            '\n' => escaped.push(c),
            '\0' => escaped.push_str("\\0"),
            '\t' => escaped.push_str("\\t"),
            '\r' => escaped.push_str("\\r"),
            c if c.is_control() => escaped.push_str(&format!("\\u{{{:x}}}", c as u32)),
            c => escaped.push(c),
        }
    }
    std::borrow::Cow::Owned(escaped)
}

fn to_codespan(diagnostic: &Diagnostic, source_len: usize, shown: &Shown) -> cs::Diagnostic<()> {
    let severity = match diagnostic.severity {
        Severity::Error => cs::Severity::Error,
        Severity::Warning => cs::Severity::Warning,
        Severity::Note => cs::Severity::Note,
    };
    let labels = diagnostic
        .labels
        .iter()
        .map(|label| {
            let start = label.span.start.min(source_len);
            let end = label.span.end.clamp(start, source_len);
            let style = if label.primary {
                cs::LabelStyle::Primary
            } else {
                cs::LabelStyle::Secondary
            };
            cs::Label::new(style, (), shown.offset(start)..shown.offset(end))
                .with_message(escape_controls(&label.message))
        })
        .collect();
    let mut notes: Vec<String> = diagnostic
        .notes
        .iter()
        .map(|note| escape_controls(note).into_owned())
        .collect();
    if let Some(help) = &diagnostic.help {
        notes.push(format!("help: {}", escape_controls(help)));
    }
    cs::Diagnostic::new(severity)
        .with_code(diagnostic.code)
        .with_message(escape_controls(&diagnostic.message))
        .with_labels(labels)
        .with_notes(notes)
}

/// The error codes of lagc. One code per class of mistake; the files under
/// `tests/data/errors/` show each one.
pub mod codes {
    pub const SYNTAX: &str = "E0001";
    pub const UNKNOWN_NAME: &str = "E0002";
    pub const DUPLICATE_NAME: &str = "E0003";
    pub const RESERVED_TIME: &str = "E0004";
    pub const MASS_DEPENDS_ON_STATE: &str = "E0005";
    pub const CONSTRAINT_LHS: &str = "E0006";
    pub const DOUBLE_CONSTRAINT: &str = "E0007";
    pub const MIXED_CONSTRAINT_ORDERS: &str = "E0008";
    pub const DEPENDENT_DERIVATIVE_IN_RHS: &str = "E0009";
    pub const MISSING_LAGRANGIAN: &str = "E0010";
    pub const MISSING_INITIAL: &str = "E0011";
    pub const MISSING_TIME: &str = "E0012";
    pub const INCONSISTENT_INITIAL: &str = "E0013";
    pub const BAD_TIME_SPAN: &str = "E0014";
    pub const SINGULAR_MASS_MATRIX: &str = "E0015";
    pub const INVALID_UTF8: &str = "E0016";
    // Added by the front end (additive):
    pub const UNKNOWN_FUNCTION: &str = "E0017";
    /// A statement given twice: two `lagrangian`s, two `time`s, two forces
    /// on one coordinate, two initial values for one derivative, …
    pub const DUPLICATE_STATEMENT: &str = "E0018";
    /// A name of a kind the statement does not allow (`t` in a param, a
    /// coordinate in an initial value, a point in any expression, …).
    pub const NAME_NOT_ALLOWED: &str = "E0019";
    pub const PARAM_USED_BEFORE_DECLARATION: &str = "E0020";
    pub const PRIMES_ON_NON_COORDINATE: &str = "E0021";
    /// A derivative of an order the statement does not allow (`q''` in the
    /// Lagrangian, `q'` in a position, an order beyond the state, …).
    pub const DERIVATIVE_ORDER_NOT_ALLOWED: &str = "E0022";
    pub const MISSING_POINT_FIELD: &str = "E0023";
    pub const DUPLICATE_POINT_FIELD: &str = "E0024";
    pub const DIMENSION_MISMATCH: &str = "E0025";
    /// A `force`, `initial` or `exact` target that is not a coordinate.
    pub const NOT_A_COORDINATE: &str = "E0026";
    pub const MISSING_COORDINATES: &str = "E0027";
    /// A param default, time bound or initial value that evaluates to
    /// infinity or NaN.
    pub const NON_FINITE_VALUE: &str = "E0028";
    pub const NUMBER_TOO_LARGE: &str = "E0029";
    pub const NESTING_TOO_DEEP: &str = "E0030";
    pub const NO_INDEPENDENT_COORDINATE: &str = "E0031";
    // Added by the stability work (additive):
    /// An `integrator` statement naming none of `auto`, `explicit`, `stiff`.
    pub const UNKNOWN_INTEGRATOR: &str = "E0032";
    /// Equations (4) disagree with the multiplier route (or the two cannot
    /// be compared at enough points): `mechanics::derive_checked`.
    pub const CROSS_CHECK_FAILED: &str = "E0033";
    // Language v2 (SPEC §2.2):
    /// A vector where a number is needed, a condition where a number is
    /// needed, or the reverse; vectors of different sizes.
    pub const TYPE_MISMATCH: &str = "E0034";
    /// A function called with the wrong number of arguments.
    pub const WRONG_ARGUMENT_COUNT: &str = "E0035";
    /// `.w`, or `.z` of a 2-vector.
    pub const UNKNOWN_COMPONENT: &str = "E0036";
    /// A `let` used before its definition (a cycle included).
    pub const LET_BEFORE_DEFINITION: &str = "E0037";
    /// A `for` candidate that is not a derivative of the constraint's order
    /// occurring in it, or a constraint not linear in its candidate.
    pub const BAD_CANDIDATE: &str = "E0038";
    /// A constraint of order k ≥ 3 whose derivative with respect to the
    /// highest derivatives holds derivatives above the second: (4) is then
    /// of order above 2, and differentiating it k − 2 times (SPEC §1.4)
    /// passes the state.
    pub const UNSUPPORTED_REDUCTION: &str = "E0039";
    /// Implicit constraints with several candidates whose other candidates'
    /// reduced systems switch (`if`, `abs`, …) on a function the first
    /// candidate's does not: every mode reads the first mode's branches.
    pub const UNSHARED_SWITCHES: &str = "E0040";
    // Impacts (SPEC §2.3):
    /// A `when` that resets a component the run does not integrate freely:
    /// a dependent derivative a constraint fixes (lagc recomputes it after
    /// the reset), or any component where the fixed ones change along the
    /// run (several candidates) or follow from (4) (constraints of order ≥ 3).
    pub const RESET_OF_FIXED_COMPONENT: &str = "E0041";
    /// An `input` where a signal set from outside cannot stand: in the
    /// Lagrangian, a mass law, a position, a holonomic constraint, an
    /// exact solution, an impact, a constant (SPEC §2.3), or a default
    /// that is not a number.
    pub const INPUT_NOT_ALLOWED: &str = "E0042";
    /// A `when` whose condition holds at the start, with the initial values
    /// the file states (constants): the state starts inside the region the
    /// impact forbids, where no impact fires (SPEC §2.3).
    pub const IMPACT_HOLDS_AT_START: &str = "E0043";
    // Added by the field method (additive); notes get their own series.
    /// The reduced system is not affine in the state (or is implicit): the
    /// linear ansatz (10) is not a complete solution, and the generated
    /// crate uses the local field method.
    pub const LOCAL_FIELD_METHOD: &str = "N0001";
    /// A given initial position of a holonomic constraint's dependent
    /// coordinate that Newton moved onto the constraints (SPEC §2.3).
    pub const INITIAL_POSITION_CORRECTED: &str = "N0002";
    /// An initial position of a holonomic constraint's dependent coordinate
    /// that the file does not give: Newton from 0 put it on the constraints
    /// (SPEC §2.3).
    pub const INITIAL_POSITION_COMPLETED: &str = "N0003";
    // Warnings (a model that still compiles) get their own series.
    /// A number literal too small for f64: it is read as 0.
    pub const LITERAL_UNDERFLOWS: &str = "W0001";
    pub const ATAN2_IN_POSITION_CONSTRAINT: &str = "W0002";
    /// An internal error of the code generator (a bug, never the model's).
    pub const CODE_GENERATION: &str = "E0900";
}
