//! pest errors → [`Diagnostic`]s that say, in words, what was expected.

use super::grammar::{is_statement_keyword, Rule};
use crate::diagnostic::{codes, Diagnostic};
use crate::span::Span;
use pest::error::{Error, ErrorVariant, InputLocation};

const STATEMENT_KEYWORDS: &str =
    "`param`, `input`, `coord`, `mass`, `lagrangian`, `constraint`, `point`, `force`, `initial`, `time`, `exact`, `integrator`, `let`, `output`, `stop` or `when`";
const POINT_FIELDS: &str =
    "`mass = …;`, `position = (…);`, `absolute velocity = (…);` or `relative velocity = (…);`";

pub fn from_pest(error: &Error<Rule>, source: &str) -> Diagnostic {
    let position = match error.location {
        InputLocation::Pos(position) => position,
        InputLocation::Span((start, _)) => start,
    };
    let position = position.min(source.len());
    let (found_span, found) = found_token(source, position);
    match &error.variant {
        ErrorVariant::ParsingError { positives, .. } => {
            expected(positives, source, found_span, &found)
        }
        // pest's own call and stack limits: a second guard behind the
        // parenthesis pre-scan.
        ErrorVariant::CustomError { message } => Diagnostic::error(
            codes::NESTING_TOO_DEEP,
            format!("the file is nested too deeply to parse ({message})"),
        )
        .with_primary(found_span, "parsing gave up here"),
    }
}

fn expected(positives: &[Rule], source: &str, found_span: Span, found: &str) -> Diagnostic {
    if let Some(diagnostic) = equality(positives, source, found_span) {
        return diagnostic;
    }
    let in_point = positives.iter().any(|&rule| is_point_field(rule));
    let mut words: Vec<&'static str> = Vec::new();
    // `when` after `stop` is a keyword expected; where a statement may
    // start, it begins one (an impact).
    let at_statement = positives.iter().any(|&rule| is_statement(rule));
    for &rule in positives {
        let word = if rule == Rule::kw_when && at_statement {
            Some("a statement")
        } else {
            describe(rule, in_point)
        };
        if let Some(word) = word {
            if !words.contains(&word) {
                words.push(word);
            }
        }
    }
    // An opening parenthesis is only ever a possibility (of a call); when
    // anything else is expected it just adds noise.
    if words.len() > 1 {
        words.retain(|&word| word != "`(`" && word != COMPONENT);
    }
    words.sort_by_key(|&word| WORD_ORDER.iter().position(|&w| w == word));
    let expected = join_or(&words);
    let message = if expected.is_empty() {
        format!("unexpected {found}")
    } else {
        format!("expected {expected}, found {found}")
    };
    let diagnostic = Diagnostic::error(codes::SYNTAX, message);
    let expects_semicolon = positives.contains(&Rule::semi);
    let previous_end = end_of_previous_token(source, found_span.start);
    if expects_semicolon && source[previous_end..found_span.start].contains('\n') {
        // The statement most likely just lacks its `;`: point where it goes.
        return diagnostic
            .with_primary(Span::new(previous_end, previous_end), "expected `;` here")
            .with_secondary(found_span, "the next statement starts here")
            .with_help("every statement ends with `;`");
    }
    let label = if expected.is_empty() {
        "unexpected here".to_string()
    } else {
        format!("expected {expected}")
    };
    let diagnostic = diagnostic.with_primary(found_span, label);
    if words.contains(&"a statement") {
        diagnostic.with_help(format!("a statement starts with {STATEMENT_KEYWORDS}"))
    } else if words.contains(&"a point field") {
        diagnostic.with_help(format!("a point holds {POINT_FIELDS}"))
    } else if expects_semicolon {
        diagnostic.with_help("every statement ends with `;`")
    } else {
        diagnostic
    }
}

/// `==` or `!=` where an operator may follow: the language compares reals
/// only by order (an equality holds at instants, which no switch follows);
/// pest alone said "expected `then` or an operator, found `=`".
fn equality(positives: &[Rule], source: &str, found_span: Span) -> Option<Diagnostic> {
    let rest = &source[found_span.start..];
    let operator = ["==", "!="].into_iter().find(|op| rest.starts_with(op))?;
    if !positives.contains(&Rule::cmp_op) && !positives.contains(&Rule::add_op) {
        return None;
    }
    let span = Span::new(found_span.start, found_span.start + 2);
    Some(
        Diagnostic::error(
            codes::SYNTAX,
            format!("`{operator}` is not an operator of the language"),
        )
        .with_primary(span, "no equality of real values")
        .with_help(
            "conditions compare by order, `<`, `<=`, `>`, `>=`, combined with `and`, `or`, \
             `not`; two real values are equal only at instants, which no switch can follow \
             (`abs(a - b) < 1e-9` is a band around them)",
        ),
    )
}

/// A vector component: possible after almost any operand, so named only
/// when nothing else is expected.
const COMPONENT: &str = "a component (`.x`)";

/// The order in which expected things are listed.
const WORD_ORDER: &[&str] = &[
    "`;`",
    "`=`",
    "`,`",
    "`..`",
    "`)`",
    "`}`",
    "`(`",
    "`velocity`",
    "an operator",
    "an expression",
    "a name",
    "a vector `(…)`",
    "a point field",
    "a statement",
    "end of file",
];

fn describe(rule: Rule, in_point: bool) -> Option<&'static str> {
    Some(match rule {
        Rule::semi => "`;`",
        Rule::eq => "`=`",
        Rule::comma => "`,`",
        Rule::range => "`..`",
        Rule::lparen => "`(`",
        Rule::rparen => "`)`",
        Rule::lbrace => "`{`",
        Rule::rbrace => "`}`",
        Rule::kw_velocity => "`velocity`",
        Rule::add_op | Rule::mul_op | Rule::pow_op | Rule::cmp_op => "an operator",
        Rule::kw_then => "`then`",
        Rule::kw_else => "`else`",
        Rule::kw_when => "`when`",
        Rule::kw_and | Rule::kw_or => "an operator",
        Rule::candidates | Rule::kw_for => "`for`",
        Rule::component => COMPONENT,
        Rule::expr
        | Rule::conditional
        | Rule::disjunction
        | Rule::conjunction
        | Rule::negation
        | Rule::comparison
        | Rule::sum
        | Rule::postfix
        | Rule::kw_not
        | Rule::kw_if
        | Rule::product
        | Rule::unary
        | Rule::power
        | Rule::call
        | Rule::paren
        | Rule::number
        | Rule::var
        | Rule::neg
        | Rule::initial_value
        | Rule::reset => "an expression",
        Rule::ident => "a name",
        Rule::kw_mass | Rule::mass if in_point => "a point field",
        rule if is_point_field(rule) => "a point field",
        rule if is_statement(rule) => "a statement",
        Rule::EOI => "end of file",
        // A prime is always optional after a name; listing it adds noise.
        _ => return None,
    })
}

fn is_point_field(rule: Rule) -> bool {
    matches!(
        rule,
        Rule::point_mass
            | Rule::point_position
            | Rule::absolute_velocity
            | Rule::relative_velocity
            | Rule::kw_position
            | Rule::kw_absolute
            | Rule::kw_relative
    )
}

fn is_statement(rule: Rule) -> bool {
    is_statement_keyword(rule)
        || matches!(
            rule,
            Rule::param
                | Rule::input
                | Rule::coords
                | Rule::mass
                | Rule::lagrangian
                | Rule::constraint
                | Rule::point
                | Rule::force
                | Rule::initial
                | Rule::time
                | Rule::exact
                | Rule::integrator
                | Rule::let_def
                | Rule::output
                | Rule::stop
                | Rule::impact
        )
}

/// "`a`, `b` or `c`".
fn join_or(words: &[&str]) -> String {
    match words {
        [] => String::new(),
        [one] => one.to_string(),
        [init @ .., last] => format!("{} or {last}", init.join(", ")),
    }
}

/// The span and a description of the token at `position`.
fn found_token(source: &str, position: usize) -> (Span, String) {
    let rest = &source[position..];
    let Some(first) = rest.chars().next() else {
        return (Span::new(position, position), "end of file".to_string());
    };
    let word_len = if first.is_ascii_alphanumeric() || first == '_' {
        rest.find(|c: char| !(c.is_ascii_alphanumeric() || c == '_' || c == '.'))
            .unwrap_or(rest.len())
    } else {
        first.len_utf8()
    };
    let span = Span::new(position, position + word_len);
    let text = &rest[..word_len];
    let description = if first.is_ascii_graphic() {
        format!("`{text}`")
    } else {
        format!("{first:?}")
    };
    (span, description)
}

/// The end of the last token before `position`: whitespace and `//`
/// comments skipped backwards.
fn end_of_previous_token(source: &str, position: usize) -> usize {
    let mut end = position;
    loop {
        let trimmed = source[..end].trim_end();
        let line_start = trimmed.rfind('\n').map_or(0, |i| i + 1);
        match trimmed[line_start..].find("//") {
            Some(comment) => end = line_start + comment,
            None => return trimmed.len(),
        }
    }
}
