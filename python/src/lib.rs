//! lagc-python: the Python module of a model, model-independent half.
//!
//! `lagc build FILE --python -o DIR` writes a maturin project whose
//! `src/lib.rs` is the model's generated code and a few lines that hand the
//! model to [`register`]; everything else a Python user meets is here,
//! compiled once and shared by every model:
//!
//! | module | what |
//! |---|---|
//! | `model` | `Model(**params)`: `solve`, `solve_batch`, `rhs`, `jacobian`, pickling |
//! | `solution` | `Solution`: `.t`, `.y`, `sol["q1"]`, `.outputs`, `.stats`, `.stopped_at` |
//! | `integration` | `Integration` (`Model.integration`): `advance_to(t)`, `.t`, `.state`, `restart` |
//! | `errors` | `IntegrationError` (shared by every model: `lagc.IntegrationError`), `KeyError`s naming the known names |
//! | `request` | Python arguments → a `lagc_runtime::table::Request` |
//! | `linear` | `Model.linearize`: the compiler's symbolic linearization (`Linear`, printed into the module) evaluated at a point |
//!
//! The runs are the runtime's (`lagc_runtime::table`): a solve's rows are
//! those `lagc run` prints, bit for bit. The GIL is released while they run.
//!
//! One extension module holds one model: [`register`] records it in a
//! static of this crate, which every module links on its own.

use lagc_runtime::model::{DynModel, Model};
use pyo3::prelude::*;
use pyo3::types::PyType;
use std::sync::OnceLock;

mod errors;
mod integration;
mod linear;
mod model;
mod request;
mod solution;

pub use linear::{Linear, LinearLayout};
pub use pyo3;

/// The model of this extension module, as the Python classes need it.
pub(crate) struct Kind {
    /// The Python module's name (`paper`).
    pub module: String,
    /// The model with these param values.
    pub make: fn(&[f64]) -> Box<dyn DynModel>,
    /// The linearization at a point (`Model.linearize`).
    pub linearize: fn(&linear::Request, &[&str]) -> Result<linear::Linearization, String>,
    /// The model with the file's param values (the prototype of a run).
    pub defaults: Vec<f64>,
    pub param_names: &'static [&'static str],
    pub state_names: &'static [&'static str],
    pub output_names: &'static [&'static str],
    pub input_names: &'static [&'static str],
    /// `lagc.IntegrationError`.
    pub error: Py<PyType>,
}

impl Kind {
    /// The model with the file's param values.
    pub fn prototype(&self) -> Box<dyn DynModel> {
        (self.make)(&self.defaults)
    }
}

static KIND: OnceLock<Kind> = OnceLock::new();

pub(crate) fn kind() -> &'static Kind {
    KIND.get()
        .expect("lagc_python::register runs when the module is imported")
}

fn make<M: Model + 'static>(params: &[f64]) -> Box<dyn DynModel> {
    Box::new(M::new(params))
}

/// Fills the Python module `module` with the classes of model `M`:
/// `Model`, `Solution`, `Integration`, `IntegrationError`. Called from the generated
/// `#[pymodule]` function; `name` is the name users import (`paper`: maturin
/// installs the extension as `paper.paper` inside the package `paper`).
pub fn register<M: Model + Linear + 'static>(
    module: &Bound<'_, PyModule>,
    name: &str,
) -> PyResult<()> {
    let py = module.py();
    let name = name.to_string();
    let error = errors::integration_error(py)?;
    let kind = Kind {
        module: name.clone(),
        make: make::<M>,
        linearize: linear::linearize::<M>,
        defaults: M::parameters(&vec![None; M::PARAMS.len()]),
        param_names: M::PARAMS,
        state_names: M::STATE,
        output_names: M::OUTPUTS,
        input_names: M::INPUTS,
        error: error.clone_ref(py),
    };
    if KIND.set(kind).is_err() && kind_name() != name {
        return Err(pyo3::exceptions::PyImportError::new_err(format!(
            "this extension module already holds the model `{}`",
            kind_name()
        )));
    }
    module.add_class::<model::PyModel>()?;
    module.add_class::<solution::PySolution>()?;
    module.add_class::<integration::PyIntegration>()?;
    module.add("IntegrationError", error.bind(py))?;
    module.add("__lagc_model__", M::NAME)?;
    // The classes are `paper.Model`, `paper.Solution`: pickle finds them by
    // these names (a Dask worker imports `paper` to rebuild a model).
    for class in ["Model", "Solution", "Integration"] {
        module.getattr(class)?.setattr("__module__", &name)?;
    }
    Ok(())
}

fn kind_name() -> &'static str {
    KIND.get().map_or("", |k| k.module.as_str())
}
