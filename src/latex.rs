//! LaTeX lines for `align*`: an equation whose sides are long sums is
//! broken at its top-level `+`/`−` into continuation lines, so that no
//! line of a paper runs off the page.

/// Source characters per line before a side is broken: rendered LaTeX is
/// about half as wide as its source, so this fills a page's text width.
const WIDTH: usize = 150;

/// The top-level terms of a LaTeX sum, each with its sign: `a + b - c` →
/// `["a", "+ b", "- c"]`. Braces and `\left`/`\right` pairs nest.
pub fn terms(latex: &str) -> Vec<String> {
    let bytes = latex.as_bytes();
    let mut depth: i32 = 0;
    let mut terms = Vec::new();
    let mut start = 0;
    let mut i = 0;
    while i < bytes.len() {
        match bytes[i] {
            b'{' => depth += 1,
            b'}' => depth -= 1,
            b'\\' if latex[i..].starts_with("\\left") => depth += 1,
            b'\\' if latex[i..].starts_with("\\right") => depth -= 1,
            b'\\' if latex[i..].starts_with("\\begin") => depth += 1,
            b'\\' if latex[i..].starts_with("\\end") => depth -= 1,
            b' ' if depth == 0
                && i > start
                && (latex[i..].starts_with(" + ") || latex[i..].starts_with(" - ")) =>
            {
                terms.push(latex[start..i].trim().to_string());
                start = i + 1;
            }
            _ => {}
        }
        i += 1;
    }
    terms.push(latex[start..].trim().to_string());
    terms.retain(|t| !t.is_empty());
    terms
}

/// The top-level group of `term` worth breaking into: the longest
/// `\left(…\right)` or `\frac{…}{…}`, as `(start, end, kind)` byte ranges.
fn longest_group(term: &str) -> Option<(usize, usize, bool)> {
    let bytes = term.as_bytes();
    let mut best: Option<(usize, usize, bool)> = None;
    let mut i = 0;
    while i < bytes.len() {
        let rest = &term[i..];
        let (is_left, open) = if rest.starts_with("\\left") {
            (true, true)
        } else if rest.starts_with("\\frac{") {
            (false, true)
        } else {
            (false, false)
        };
        if !open {
            // Skip other groups whole: only top-level ones are candidates.
            if bytes[i] == b'{' {
                i = matching_brace(term, i).map_or(bytes.len(), |e| e + 1);
                continue;
            }
            i += 1;
            continue;
        }
        let end = if is_left {
            matching_right(term, i)
        } else {
            let num = i + "\\frac".len();
            matching_brace(term, num)
                .and_then(|e| matching_brace(term, e + 1))
                .map(|e| e + 1)
        };
        let Some(end) = end else {
            return best;
        };
        if best.is_none_or(|(s, e, _)| end - i > e - s) {
            best = Some((i, end, is_left));
        }
        i = end;
    }
    best
}

/// The index of the `}` closing the `{` at `open`.
fn matching_brace(s: &str, open: usize) -> Option<usize> {
    let mut depth = 0;
    for (k, b) in s.bytes().enumerate().skip(open) {
        match b {
            b'{' => depth += 1,
            b'}' => {
                depth -= 1;
                if depth == 0 {
                    return Some(k);
                }
            }
            _ => {}
        }
    }
    None
}

/// The end (exclusive, after its delimiter) of the `\right` matching the
/// `\left` at `start`.
fn matching_right(s: &str, start: usize) -> Option<usize> {
    let mut depth = 0;
    let mut k = start;
    while k < s.len() {
        if s[k..].starts_with("\\left") {
            depth += 1;
            k += 5;
        } else if s[k..].starts_with("\\right") {
            depth -= 1;
            k += 6;
            if depth == 0 {
                // The delimiter after `\right` (`)`, `.`, `]`, …).
                return Some((k + 1).min(s.len()));
            }
        } else {
            k += 1;
        }
    }
    None
}

/// `term` as pieces to be laid out on lines: an overlong product is opened
/// at its longest parenthesis (a long fraction first written as a product
/// with a reciprocal), whose terms become pieces in turn.
fn pieces(term: &str, out: &mut Vec<String>) {
    if term.len() <= WIDTH {
        out.push(term.to_string());
        return;
    }
    let Some((start, end, is_left)) = longest_group(term) else {
        out.push(term.to_string());
        return;
    };
    if !is_left {
        let num_open = start + "\\frac".len();
        let num_close = matching_brace(term, num_open).unwrap_or(num_open);
        let numerator = &term[num_open + 1..num_close];
        let denominator = &term[num_close + 2..end - 1];
        let rewritten = format!(
            "{}\\left({numerator}\\right) \\left({denominator}\\right)^{{-1}}{}",
            &term[..start],
            &term[end..]
        );
        if rewritten.len() > term.len() + 64 || !rewritten.contains("\\left(") {
            out.push(term.to_string());
        } else {
            pieces(&rewritten, out);
        }
        return;
    }
    let open_end = start + "\\left(".len();
    let close_start = term[..end].rfind("\\right").unwrap_or(end);
    let inner = &term[open_end..close_start];
    let inner_terms = terms(inner);
    if inner_terms.len() < 2 && inner.len() == term.len() - 14 {
        out.push(term.to_string());
        return;
    }
    out.push(format!("{}\\left(", &term[..start]));
    for t in inner_terms {
        pieces(&t, out);
    }
    out.push(term[close_start..].to_string());
}

/// `side` laid out on lines of about [`WIDTH`] characters, each line's
/// `\left`/`\right` balanced with invisible `\left.`/`\right.`.
fn lines(side: &str) -> Vec<String> {
    let mut all = Vec::new();
    for term in terms(side) {
        pieces(&term, &mut all);
    }
    let mut packed: Vec<String> = Vec::new();
    for piece in all {
        match packed.last_mut() {
            Some(line) if line.len() + piece.len() < WIDTH => {
                line.push(' ');
                line.push_str(&piece);
            }
            _ => packed.push(piece),
        }
    }
    packed.iter().map(|l| balanced(l)).collect()
}

/// `line` with `\left.` before it for every `\right` it closes and
/// `\right.` after it for every `\left` it leaves open.
fn balanced(line: &str) -> String {
    let mut open = 0usize;
    let mut unmatched_closes = 0usize;
    let mut k = 0;
    while k < line.len() {
        if line[k..].starts_with("\\left") {
            open += 1;
            k += 5;
        } else if line[k..].starts_with("\\right") {
            if open > 0 {
                open -= 1;
            } else {
                unmatched_closes += 1;
            }
            k += 6;
        } else {
            k += 1;
        }
    }
    format!(
        "{}{line}{}",
        "\\left. ".repeat(unmatched_closes),
        " \\right.".repeat(open)
    )
}

/// One equation of an `align*` block, `lhs = rhs` tagged `tag`: on one line
/// when it fits, else each side broken into continuation lines.
pub fn equation(lhs: &str, rhs: &str, tag: &str) -> String {
    if lhs.len() + rhs.len() < WIDTH {
        return format!("  {lhs} &= {rhs} && {tag} \\\\\n");
    }
    let left = lines(lhs);
    let right = lines(rhs);
    let mut out = String::new();
    if left.len() == 1 {
        out.push_str(&format!("  {} ", left[0]));
    } else {
        for (i, line) in left.iter().enumerate() {
            if i == 0 {
                out.push_str(&format!("  & {line} \\\\\n"));
            } else {
                out.push_str(&format!("  &\\quad {line} \\\\\n"));
            }
        }
        out.push_str("  ");
    }
    for (i, line) in right.iter().enumerate() {
        let last = i + 1 == right.len();
        let end = if last {
            format!(" && {tag} \\\\\n")
        } else {
            " \\\\\n".to_string()
        };
        if i == 0 {
            out.push_str(&format!("&= {line}{end}"));
        } else {
            out.push_str(&format!("  &\\quad {line}{end}"));
        }
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn top_level_terms_only() {
        assert_eq!(
            terms("a + \\left(b - c\\right) - \\frac{d + e}{f}"),
            ["a", "+ \\left(b - c\\right)", "- \\frac{d + e}{f}"]
        );
        assert_eq!(terms("-a + b"), ["-a", "+ b"]);
    }

    #[test]
    fn long_equations_break_at_terms_and_keep_their_tag() {
        let long: Vec<String> = (0..40).map(|i| format!("x_{{{i}}}")).collect();
        let rhs = long.join(" + ");
        let out = equation("y", &rhs, "\\text{(7)}");
        assert!(out.lines().count() > 1, "{out}");
        assert!(out.lines().last().unwrap().ends_with("&& \\text{(7)} \\\\"));
        assert!(out.starts_with("  y &= x_{0}"));
        assert_eq!(equation("y", "x", "t"), "  y &= x && t \\\\\n");
    }

    #[test]
    fn a_long_product_opens_at_its_parenthesis_and_every_line_balances() {
        let inner: Vec<String> = (0..60).map(|i| format!("a_{{{i}}}")).collect();
        let term = format!("m \\left({}\\right) x", inner.join(" + "));
        let out = lines(&term);
        assert!(out.len() > 1, "{out:?}");
        for line in &out {
            assert_eq!(
                line.matches("\\left").count(),
                line.matches("\\right").count(),
                "{line}"
            );
        }
        let long_fraction = format!("\\frac{{{}}}{{b}}", inner.join(" + "));
        assert!(lines(&long_fraction).len() > 1);
    }
}
