//! The generated binary's `--summary json` line: one flat JSON object
//! (strings, numbers, `null`, booleans), written by hand there and read by
//! hand here — a few dozen lines instead of a serde dependency.

/// What one run of the generated binary reports.
#[derive(Clone, Debug, PartialEq)]
pub struct RunSummary {
    /// e.g. `field (DOP853)`.
    pub method: String,
    pub steps: u64,
    pub rhs_evaluations: u64,
    /// The smallest wall time of the timed solves, in seconds.
    pub wall_time_s: f64,
    pub largest_condition: Option<f64>,
    pub reanchorings: Option<u64>,
    /// Against the model's `exact` lines; `None` when it has none.
    pub exact_error: Option<f64>,
}

#[derive(Clone, Debug, PartialEq)]
enum Value {
    Text(String),
    Number(f64),
    Bool(bool),
    Null,
}

/// The summary from the binary's stderr: its last line that opens with
/// `{`. A failed run's `{"failed":true,"message":…}` is `Err(message)`.
pub fn parse_summary(stderr: &str) -> Result<RunSummary, String> {
    let line = stderr
        .lines()
        .rev()
        .map(str::trim)
        .find(|l| l.starts_with('{'))
        .ok_or("no JSON summary line on stderr")?;
    let fields = parse_object(line)?;
    let get = |key: &str| fields.iter().find(|(k, _)| k == key).map(|(_, v)| v);
    if let Some(Value::Bool(true)) = get("failed") {
        return Err(match get("message") {
            Some(Value::Text(message)) => message.clone(),
            _ => "failed without a message".to_string(),
        });
    }
    let number = |key: &str| match get(key) {
        Some(Value::Number(v)) => Ok(Some(*v)),
        Some(Value::Null) | None => Ok(None),
        Some(_) => Err(format!("`{key}` is not a number")),
    };
    let required = |key: &str| number(key)?.ok_or_else(|| format!("no `{key}` in the summary"));
    let count = |v: f64| v as u64;
    Ok(RunSummary {
        method: match get("method") {
            Some(Value::Text(m)) => m.clone(),
            _ => return Err("no `method` in the summary".to_string()),
        },
        steps: count(required("steps")?),
        rhs_evaluations: count(required("rhs_evaluations")?),
        wall_time_s: required("wall_time_s")?,
        largest_condition: number("largest_condition")?,
        reanchorings: number("reanchorings")?.map(count),
        exact_error: number("exact_error")?,
    })
}

/// `{"key":value,…}` with scalar values only.
fn parse_object(text: &str) -> Result<Vec<(String, Value)>, String> {
    let mut chars = text.chars().peekable();
    let mut fields = Vec::new();
    let bad = || format!("not a flat JSON object: {text}");
    skip_space(&mut chars);
    if chars.next() != Some('{') {
        return Err(bad());
    }
    skip_space(&mut chars);
    if chars.peek() == Some(&'}') {
        return Ok(fields);
    }
    loop {
        skip_space(&mut chars);
        if chars.next() != Some('"') {
            return Err(bad());
        }
        let key = parse_string(&mut chars).ok_or_else(bad)?;
        skip_space(&mut chars);
        if chars.next() != Some(':') {
            return Err(bad());
        }
        skip_space(&mut chars);
        let value = match chars.peek() {
            Some('"') => {
                chars.next();
                Value::Text(parse_string(&mut chars).ok_or_else(bad)?)
            }
            _ => {
                let mut word = String::new();
                while let Some(&c) = chars.peek() {
                    if c == ',' || c == '}' || c.is_whitespace() {
                        break;
                    }
                    word.push(c);
                    chars.next();
                }
                match word.as_str() {
                    "null" => Value::Null,
                    "true" => Value::Bool(true),
                    "false" => Value::Bool(false),
                    _ => Value::Number(word.parse().map_err(|_| bad())?),
                }
            }
        };
        fields.push((key, value));
        skip_space(&mut chars);
        match chars.next() {
            Some(',') => continue,
            Some('}') => return Ok(fields),
            _ => return Err(bad()),
        }
    }
}

fn skip_space(chars: &mut std::iter::Peekable<std::str::Chars<'_>>) {
    while chars.peek().is_some_and(|c| c.is_whitespace()) {
        chars.next();
    }
}

/// The rest of a string after its opening quote.
fn parse_string(chars: &mut std::iter::Peekable<std::str::Chars<'_>>) -> Option<String> {
    let mut out = String::new();
    loop {
        match chars.next()? {
            '"' => return Some(out),
            '\\' => match chars.next()? {
                'n' => out.push('\n'),
                't' => out.push('\t'),
                'r' => out.push('\r'),
                'u' => {
                    let hex: String = (0..4).filter_map(|_| chars.next()).collect();
                    out.push(char::from_u32(u32::from_str_radix(&hex, 16).ok()?)?);
                }
                c => out.push(c),
            },
            c => out.push(c),
        }
    }
}
