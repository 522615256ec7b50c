//! The FMU's crate and its modelDescription.xml (FMI 2.0 co-simulation):
//! the model's generated `lib.rs` with one line that exports the FMI
//! functions of the `lagc-fmu` library, a `cdylib`; and the description
//! of its variables. Pure: the CLI builds, zips and writes.
//!
//! Value references follow `lagc-fmu`'s `instance.rs`: the params, the
//! state, the outputs, the inputs, in that order.

use super::{emit_crate, EmitOptions, GeneratedCrate};
use crate::diagnostic::Diagnostic;
use crate::ir::Symbol;
use crate::kernel::{InitialKind, InitialSource, Kernel};
use std::fmt::Write;

/// The lagc-fmu library's files, relative to its root.
const LIBRARY: &[(&str, &str)] = &[
    ("Cargo.toml", include_str!("../../fmu/Cargo.toml")),
    ("src/lib.rs", include_str!("../../fmu/src/lib.rs")),
    ("src/ffi.rs", include_str!("../../fmu/src/ffi.rs")),
    ("src/instance.rs", include_str!("../../fmu/src/instance.rs")),
];

/// The lagc-fmu library's sources (it sits beside the runtime, whose
/// path its `Cargo.toml` names as `../runtime`).
pub fn fmu_library_files() -> impl Iterator<Item = (&'static str, &'static str)> {
    LIBRARY.iter().copied()
}

/// The indices of the params an importer may tune, `0, 2`.
fn tunable_indices(kernel: &Kernel) -> String {
    let indices: Vec<String> = kernel
        .params
        .iter()
        .enumerate()
        .filter(|(_, p)| p.tunable)
        .map(|(i, _)| i.to_string())
        .collect();
    indices.join(", ")
}

/// An FMU's crate, its modelDescription.xml and its model identifier
/// (the shared library's name in the archive).
#[derive(Debug, Clone, PartialEq)]
pub struct FmuCrate {
    pub generated: GeneratedCrate,
    pub model_identifier: String,
    pub model_description: String,
}

/// The FMU crate of `kernel`: the generated crate as a `cdylib`
/// depending on lagc-fmu at `fmu_path` (and the runtime at
/// `options.runtime_path`), without its binary.
pub fn emit_fmu(
    kernel: &Kernel,
    options: &EmitOptions,
    fmu_path: &str,
) -> Result<FmuCrate, Vec<Diagnostic>> {
    let mut generated = emit_crate(kernel, options)?;
    let library = super::library_name(&generated.package);
    let runtime = &options.runtime_path;
    let package = &generated.package;
    let cargo = super::files::cdylib_cargo_toml(
        "--fmu",
        package,
        &library,
        &[("lagc-runtime", runtime), ("lagc-fmu", fmu_path)],
    );
    let mut files = Vec::new();
    for (path, contents) in generated.files.drain(..) {
        match path.as_str() {
            "Cargo.toml" => files.push((path, cargo.clone())),
            // Cargo writes the lock of the two path dependencies offline.
            "Cargo.lock" | "src/main.rs" => {}
            "src/lib.rs" => files.push((
                path,
                format!(
                    "{contents}\n// The FMI 2.0 co-simulation functions of this model (the \
                     params an importer may tune\n// between steps by index).\n\
                     lagc_fmu::export_fmu!(Model, tunable = [{}]);\n",
                    tunable_indices(kernel)
                ),
            )),
            _ => files.push((path, contents)),
        }
    }
    generated.files = files;
    let model_identifier = library;
    let model_description = model_description(kernel, options, &model_identifier);
    Ok(FmuCrate {
        generated,
        model_identifier,
        model_description,
    })
}

/// The Modelica-style name of state component `k`: `q`, `der(q)`,
/// `der(q,2)`.
fn state_name(kernel: &Kernel, k: usize) -> String {
    match kernel.state[k] {
        Symbol::Jet { coord, order } => {
            let q = kernel.arena.symbol_name(Symbol::Jet { coord, order: 0 });
            match order {
                0 => q,
                1 => format!("der({q})"),
                r => format!("der({q},{r})"),
            }
        }
        other => kernel.arena.symbol_name(other),
    }
}

fn xml_escape(text: &str) -> String {
    text.replace('&', "&amp;")
        .replace('<', "&lt;")
        .replace('>', "&gt;")
        .replace('"', "&quot;")
}

/// A number as XML wants it (`1e-10`, `0.5`, `-2`).
fn number(v: f64) -> String {
    format!("{v:?}")
}

/// modelDescription.xml: params as fixed parameters with their defaults;
/// the state as outputs (`initial="exact"` with the model's value where
/// it states one, `calculated` where the constraints or the equations fix
/// it); outputs; inputs with their defaults; the default experiment.
pub fn model_description(kernel: &Kernel, options: &EmitOptions, identifier: &str) -> String {
    let arena = &kernel.arena;
    // Param defaults in order (each may use the ones before it).
    let mut params: Vec<f64> = Vec::new();
    for p in &kernel.params {
        let known = params.clone();
        let env = move |s: Symbol| match s {
            Symbol::Param(i) => known.get(i as usize).copied().unwrap_or(f64::NAN),
            _ => f64::NAN,
        };
        params.push(arena.eval(p.value, &env));
    }
    let env = |s: Symbol| match s {
        Symbol::Param(i) => params.get(i as usize).copied().unwrap_or(f64::NAN),
        _ => f64::NAN,
    };
    let (t0, t1) = (
        arena.eval(kernel.time_span.0, &env),
        arena.eval(kernel.time_span.1, &env),
    );
    let mut starts: Vec<Option<f64>> = vec![None; kernel.state.len()];
    for source in &kernel.initial.sources {
        if let InitialSource::Given { index, value } = *source {
            starts[index] = Some(arena.eval(value, &env));
        }
    }
    let tolerance = lagc_runtime::driver::Options::default().tol.rtol;
    let mut x = String::new();
    let _ = writeln!(x, "<?xml version=\"1.0\" encoding=\"UTF-8\"?>");
    let _ = writeln!(
        x,
        "<fmiModelDescription fmiVersion=\"2.0\" modelName=\"{}\" guid=\"{}\" \
         description=\"{}\" generationTool=\"lagc {}\" variableNamingConvention=\"structured\" \
         numberOfEventIndicators=\"0\">",
        xml_escape(&options.model_name),
        xml_escape(&options.source_hash),
        xml_escape(&format!(
            "The {} model, compiled by lagc: its own integrators (the field method or direct) \
             inside fmi2DoStep",
            options.model_name
        )),
        env!("CARGO_PKG_VERSION"),
    );
    let _ = writeln!(
        x,
        "  <CoSimulation modelIdentifier=\"{identifier}\" \
         canHandleVariableCommunicationStepSize=\"true\" canInterpolateInputs=\"false\" \
         maxOutputDerivativeOrder=\"0\" canRunAsynchronuously=\"false\" \
         canBeInstantiatedOnlyOncePerProcess=\"false\" canNotUseMemoryManagementFunctions=\"true\" \
         canGetAndSetFMUstate=\"true\" canSerializeFMUstate=\"true\" \
         providesDirectionalDerivative=\"false\"/>"
    );
    let _ = writeln!(x, "  <LogCategories>");
    for category in ["logStatusError", "logStatusFatal", "logEvents"] {
        let _ = writeln!(x, "    <Category name=\"{category}\"/>");
    }
    let _ = writeln!(x, "  </LogCategories>");
    let _ = writeln!(
        x,
        "  <DefaultExperiment startTime=\"{}\" stopTime=\"{}\" tolerance=\"{}\"/>",
        number(t0),
        number(t1),
        number(tolerance)
    );
    let _ = writeln!(x, "  <ModelVariables>");
    let mut vr = 0;
    let mut index = 0;
    let (mut outputs, mut initial_unknowns) = (Vec::new(), Vec::new());
    let mut variable = |x: &mut String, name: &str, attributes: &str, start: Option<f64>| {
        let real = match start {
            Some(v) => format!("<Real start=\"{}\"/>", number(v)),
            None => "<Real/>".to_string(),
        };
        let _ = writeln!(
            x,
            "    <ScalarVariable name=\"{}\" valueReference=\"{vr}\" {attributes}>{real}</ScalarVariable>",
            xml_escape(name)
        );
        vr += 1;
        index += 1;
        index
    };
    for (p, value) in kernel.params.iter().zip(&params) {
        // Tunable: set between steps, the integration restarts there;
        // fixed: it enters what a change could not carry the state over
        // (`check::model::Param::tunable`).
        let variability = if p.tunable { "tunable" } else { "fixed" };
        variable(
            &mut x,
            &p.name,
            &format!("causality=\"parameter\" variability=\"{variability}\" initial=\"exact\""),
            Some(*value),
        );
    }
    for (k, start) in starts.iter().enumerate() {
        let name = state_name(kernel, k);
        let i = match (kernel.initial.kinds[k], *start) {
            (InitialKind::Given, Some(start)) => variable(
                &mut x,
                &name,
                "causality=\"output\" variability=\"continuous\" initial=\"exact\"",
                Some(start),
            ),
            _ => {
                let i = variable(
                    &mut x,
                    &name,
                    "causality=\"output\" variability=\"continuous\" initial=\"calculated\"",
                    None,
                );
                initial_unknowns.push(i);
                i
            }
        };
        outputs.push(i);
    }
    for (name, _) in &kernel.outputs {
        let i = variable(
            &mut x,
            name,
            "causality=\"output\" variability=\"continuous\" initial=\"calculated\"",
            None,
        );
        outputs.push(i);
        initial_unknowns.push(i);
    }
    for (name, default) in &kernel.inputs {
        variable(
            &mut x,
            name,
            "causality=\"input\" variability=\"continuous\"",
            Some(*default),
        );
    }
    // The run's structural parameters (lagc-fmu's Integer variables).
    let integers = [
        (
            "lagc.method",
            "the method: 0 the field method, 1 direct integration",
            0,
        ),
        (
            "lagc.integrator",
            "the integrator: 0 the model's integrator statement (else auto), 1 auto, \
             2 explicit (DOP853), 3 stiff (RODAS4), 4 Magnus (the field's linear coefficient systems)",
            0,
        ),
    ];
    for (k, (name, description, start)) in integers.iter().enumerate() {
        let _ = writeln!(
            x,
            "    <ScalarVariable name=\"{name}\" valueReference=\"{k}\" description=\"{description}\" \
             causality=\"parameter\" variability=\"fixed\" initial=\"exact\">\
             <Integer start=\"{start}\"/></ScalarVariable>"
        );
    }
    let _ = writeln!(x, "  </ModelVariables>");
    let _ = writeln!(x, "  <ModelStructure>");
    let _ = writeln!(x, "    <Outputs>");
    for i in &outputs {
        let _ = writeln!(x, "      <Unknown index=\"{i}\"/>");
    }
    let _ = writeln!(x, "    </Outputs>");
    if !initial_unknowns.is_empty() {
        let _ = writeln!(x, "    <InitialUnknowns>");
        for i in &initial_unknowns {
            let _ = writeln!(x, "      <Unknown index=\"{i}\"/>");
        }
        let _ = writeln!(x, "    </InitialUnknowns>");
    }
    let _ = writeln!(x, "  </ModelStructure>");
    let _ = writeln!(x, "</fmiModelDescription>");
    x
}
