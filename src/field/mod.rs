//! Stage 5: the field method's symbolic part (SPEC §1.5): the basic
//! equation (9) for the linear ansatz (10) and the coefficient system
//! `f' = F(t, f)`, with its Jacobians, built from the reduced system (7).
//!
//! | file | what |
//! |---|---|
//! | `basic.rs` | (9), the coefficient system, the classification |
//! | `text.rs` | the text form for `lagc derive` |

mod basic;
mod text;

pub use basic::{
    field_system, local_field_note, motion_expressions, CoefficientSystem, FieldSystem,
};
