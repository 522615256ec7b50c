//! Stage 1: `.lag` text → AST (pest grammar in `grammar/lag.pest`).

pub mod ast;
