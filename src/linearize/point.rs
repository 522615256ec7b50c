//! The request read: `NAME=VALUE` lists parsed and their names resolved,
//! the params evaluated in declaration order (an override recomputes the
//! params after it, as `--param` does at run time), the time.

use super::LinearizeError;
use crate::check::model::Model;
use crate::ir::{lower, Arena, ExprId, Symbol};

/// `NAME=VALUE` items, each item possibly a comma-separated list, in
/// order; `flag` names the option in messages.
pub(super) fn items(lists: &[String], flag: &str) -> Result<Vec<(String, f64)>, LinearizeError> {
    let mut out: Vec<(String, f64)> = Vec::new();
    for list in lists {
        for item in list.split(',') {
            let item = item.trim();
            let Some((name, value)) = item.split_once('=') else {
                return Err(LinearizeError::usage(
                    format!("`{flag} {item}` is not NAME=VALUE"),
                    format!("write e.g. `{flag} \"th=0.1,th'=0\"`"),
                ));
            };
            let (name, value) = (name.trim(), value.trim());
            if name.is_empty() {
                return Err(LinearizeError::usage(
                    format!("`{flag} {item}` has no name before `=`"),
                    format!("write e.g. `{flag} \"th=0.1\"`"),
                ));
            }
            let number = value.parse::<f64>().ok().filter(|v| v.is_finite());
            let Some(number) = number else {
                return Err(LinearizeError::usage(
                    format!("the value of `{name}` in `{flag}`, `{value}`, is not a finite number"),
                    "write a decimal number such as `0.5`, `-3` or `1e-3`",
                ));
            };
            if out.iter().any(|(n, _)| n == name) {
                return Err(LinearizeError::usage(
                    format!("`{name}` is given twice in `{flag}`"),
                    "give each name once",
                ));
            }
            out.push((name.to_string(), number));
        }
    }
    Ok(out)
}

/// The params: their lowered expressions, whether each is overridden, and
/// their values.
pub(super) struct Params {
    pub exprs: Vec<ExprId>,
    pub overridden: Vec<bool>,
    pub values: Vec<f64>,
}

pub(super) fn params(
    arena: &mut Arena,
    model: &Model,
    overrides: &[(String, f64)],
) -> Result<Params, LinearizeError> {
    let names: Vec<&str> = model.params.iter().map(|p| p.name.as_str()).collect();
    for (name, _) in overrides {
        if !names.contains(&name.as_str()) {
            let mut help = match crate::suggest::closest(name, names.iter().copied()) {
                Some(c) => format!("did you mean `{c}`? "),
                None => String::new(),
            };
            if names.is_empty() {
                help.push_str("the model has no params");
            } else {
                help.push_str(&format!("the params are {}", names.join(", ")));
            }
            return Err(LinearizeError::usage(
                format!("unknown param `{name}` in `--param`"),
                help,
            ));
        }
    }
    let exprs: Vec<ExprId> = model
        .params
        .iter()
        .map(|p| lower(arena, &p.value, model))
        .collect();
    let mut values: Vec<f64> = Vec::with_capacity(exprs.len());
    let mut overridden = Vec::with_capacity(exprs.len());
    for (i, p) in model.params.iter().enumerate() {
        let given = overrides
            .iter()
            .find(|(n, _)| *n == p.name)
            .map(|&(_, v)| v);
        overridden.push(given.is_some());
        let v = given.unwrap_or_else(|| {
            arena.eval(exprs[i], &|s| match s {
                Symbol::Param(j) => values.get(j as usize).copied().unwrap_or(f64::NAN),
                _ => f64::NAN,
            })
        });
        if !v.is_finite() {
            return Err(LinearizeError::undefined(
                format!("the param `{}` is {v} with these overrides", p.name),
                "change the params it is computed from",
            ));
        }
        values.push(v);
    }
    Ok(Params {
        exprs,
        overridden,
        values,
    })
}

/// The inputs' values at the point: `--input NAME=VALUE`, else each
/// input's default.
pub(super) fn inputs(model: &Model, given: &[(String, f64)]) -> Result<Vec<f64>, LinearizeError> {
    let names: Vec<&str> = model.inputs.iter().map(|u| u.name.as_str()).collect();
    for (name, _) in given {
        if !names.contains(&name.as_str()) {
            let mut help = match crate::suggest::closest(name, names.iter().copied()) {
                Some(c) => format!("did you mean `{c}`? "),
                None => String::new(),
            };
            if names.is_empty() {
                help.push_str("the model declares no `input`");
            } else {
                help.push_str(&format!("the inputs are {}", names.join(", ")));
            }
            return Err(LinearizeError::usage(
                format!("unknown input `{name}` in `--input`"),
                help,
            ));
        }
    }
    Ok(model
        .inputs
        .iter()
        .map(|u| {
            given
                .iter()
                .find(|(n, _)| *n == u.name)
                .map_or(u.default, |&(_, v)| v)
        })
        .collect())
}

/// The time: `--t`, else the start of the model's span.
pub(super) fn time(
    arena: &mut Arena,
    model: &Model,
    t: Option<&str>,
    params: &[f64],
) -> Result<f64, LinearizeError> {
    match t {
        Some(text) => text
            .trim()
            .parse::<f64>()
            .ok()
            .filter(|v| v.is_finite())
            .ok_or_else(|| {
                LinearizeError::usage(
                    format!("`--t {text}` is not a finite number"),
                    "write the time as a decimal number, e.g. `--t 0.5`",
                )
            }),
        None => {
            let start = lower(arena, &model.time.start, model);
            let t0 = arena.eval(start, &|s| match s {
                Symbol::Param(j) => params.get(j as usize).copied().unwrap_or(f64::NAN),
                _ => f64::NAN,
            });
            if t0.is_finite() {
                Ok(t0)
            } else {
                Err(LinearizeError::undefined(
                    format!("the model's start time is {t0} with these params"),
                    "give the time with `--t`",
                ))
            }
        }
    }
}

/// The state value `model` states for `symbol` (`initial …`), evaluated.
pub(super) fn stated(
    arena: &mut Arena,
    model: &Model,
    symbol: Symbol,
    params: &[f64],
) -> Option<f64> {
    let Symbol::Jet { coord, order } = symbol else {
        return None;
    };
    let value = model
        .initial
        .iter()
        .find(|i| i.coord as u32 == coord && i.order == order)?;
    let e = lower(arena, &value.value, model);
    Some(arena.eval(e, &|s| match s {
        Symbol::Param(j) => params.get(j as usize).copied().unwrap_or(f64::NAN),
        _ => f64::NAN,
    }))
}

/// Resolves the `--at` names against the state; an unknown name is an
/// error naming the state (and the params, when it is one).
pub(super) fn resolve_at(
    given: &[(String, f64)],
    state_names: &[String],
    model: &Model,
) -> Result<Vec<(usize, f64)>, LinearizeError> {
    let mut out = Vec::new();
    for (name, value) in given {
        match state_names.iter().position(|n| n == name) {
            Some(k) => out.push((k, *value)),
            None => {
                let mut help = String::new();
                if model.params.iter().any(|p| &p.name == name) {
                    help.push_str(&format!("`{name}` is a param: give it with `--param`; "));
                } else if let Some(c) =
                    crate::suggest::closest(name, state_names.iter().map(String::as_str))
                {
                    help.push_str(&format!("did you mean `{c}`? "));
                }
                help.push_str(&format!("the state is {}", state_names.join(", ")));
                return Err(LinearizeError::usage(
                    format!("unknown state component `{name}` in `--at`"),
                    help,
                ));
            }
        }
    }
    Ok(out)
}
