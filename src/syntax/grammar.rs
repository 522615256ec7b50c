//! The pest parser generated from `grammar/lag.pest`.

#[derive(pest_derive::Parser)]
#[grammar = "grammar/lag.pest"]
pub struct LagParser;
