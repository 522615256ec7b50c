//! The pest parser generated from `grammar/lag.pest`.

#[derive(pest_derive::Parser)]
#[grammar = "grammar/lag.pest"]
pub struct LagParser;

/// The keywords that begin a statement (`param`, `coord`, …, `let`,
/// `output`, `stop`; `when` is punctuation of `stop when` and of an
/// impact, see `parser::is_punctuation`): the parser skips them as punctuation, and a syntax
/// error before one says a statement was expected.
pub fn is_statement_keyword(rule: Rule) -> bool {
    matches!(
        rule,
        Rule::kw_param
            | Rule::kw_input
            | Rule::kw_coord
            | Rule::kw_mass
            | Rule::kw_lagrangian
            | Rule::kw_constraint
            | Rule::kw_point
            | Rule::kw_force
            | Rule::kw_initial
            | Rule::kw_time
            | Rule::kw_exact
            | Rule::kw_integrator
            | Rule::kw_let
            | Rule::kw_output
            | Rule::kw_stop
    )
}
