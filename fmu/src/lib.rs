//! lagc-fmu: the FMI 2.0 co-simulation interface of the FMUs `lagc build
//! --fmu` makes, model-independent, over lagc-runtime's `DynModel`.
//!
//! A generated FMU crate is the model's generated `lib.rs` plus one line,
//! `lagc_fmu::export_fmu!(Model);`, which exports the 34 `fmi2…`
//! functions of FMI 2.0 (common and co-simulation: FMPy looks every one
//! up when it loads the library) under their C names; each forwards to
//! [`ffi`], and [`instance`] holds the state machine in safe Rust.
//!
//! | module | what |
//! |---|---|
//! | `instance` | one instance: value references, params, start values, inputs, steps, saved states |
//! | `ffi` | the C signatures, null and panic safety, the importer's logger |

pub mod ffi;
pub mod instance;

pub use lagc_runtime;

/// Exports the FMI 2.0 co-simulation functions for the model type `$m`
/// (a `lagc_runtime::model::Model`); `tunable = [i, …]` lists the params
/// (by index) an importer may set between steps (lagc decides which:
/// `check::model::Param::tunable`), none when omitted.
#[macro_export]
macro_rules! export_fmu {
    ($m:ty) => {
        $crate::export_fmu!($m, tunable = []);
    };
    ($m:ty, tunable = [$($tunable:expr),* $(,)?]) => {
        /// The model the FMU's functions make instances of.
        type LagcFmuModel = $m;
        /// The params an importer may tune between steps.
        const LAGC_FMU_TUNABLE: &[usize] = &[$($tunable),*];

        mod fmi2 {
            #![allow(non_snake_case, clippy::missing_safety_doc)]
            use std::ffi::{c_char, c_void};
            use $crate::ffi;
            use $crate::lagc_runtime::model::{DynModel, Model as _};

            fn prototype() -> Box<dyn DynModel> {
                let params =
                    <super::LagcFmuModel as $crate::lagc_runtime::model::Model>::parameters(&[]);
                Box::new(<super::LagcFmuModel as $crate::lagc_runtime::model::Model>::new(&params))
            }

            #[no_mangle]
            pub extern "C" fn fmi2GetTypesPlatform() -> *const c_char {
                ffi::get_types_platform()
            }
            #[no_mangle]
            pub extern "C" fn fmi2GetVersion() -> *const c_char {
                ffi::get_version()
            }
            #[no_mangle]
            pub unsafe extern "C" fn fmi2SetDebugLogging(
                c: *mut c_void,
                on: i32,
                _n: usize,
                _categories: *const *const c_char,
            ) -> i32 {
                unsafe { ffi::set_debug_logging(c, on) }
            }
            #[no_mangle]
            pub unsafe extern "C" fn fmi2Instantiate(
                name: *const c_char,
                fmu_type: i32,
                guid: *const c_char,
                resources: *const c_char,
                callbacks: *const ffi::Callbacks,
                visible: i32,
                logging: i32,
            ) -> *mut c_void {
                unsafe {
                    ffi::instantiate(
                        prototype,
                        super::LAGC_FMU_TUNABLE,
                        name, fmu_type, guid, resources, callbacks, visible, logging,
                    )
                }
            }
            #[no_mangle]
            pub unsafe extern "C" fn fmi2FreeInstance(c: *mut c_void) {
                unsafe { ffi::free_instance(c) }
            }
            #[no_mangle]
            pub unsafe extern "C" fn fmi2SetupExperiment(
                c: *mut c_void,
                tolerance_defined: i32,
                tolerance: f64,
                start: f64,
                stop_defined: i32,
                stop: f64,
            ) -> i32 {
                unsafe {
                    ffi::setup_experiment(
                        c,
                        tolerance_defined,
                        tolerance,
                        start,
                        stop_defined,
                        stop,
                    )
                }
            }
            #[no_mangle]
            pub unsafe extern "C" fn fmi2EnterInitializationMode(c: *mut c_void) -> i32 {
                unsafe { ffi::enter_initialization_mode(c) }
            }
            #[no_mangle]
            pub unsafe extern "C" fn fmi2ExitInitializationMode(c: *mut c_void) -> i32 {
                unsafe { ffi::exit_initialization_mode(c) }
            }
            #[no_mangle]
            pub unsafe extern "C" fn fmi2Terminate(c: *mut c_void) -> i32 {
                unsafe { ffi::terminate(c) }
            }
            #[no_mangle]
            pub unsafe extern "C" fn fmi2Reset(c: *mut c_void) -> i32 {
                unsafe { ffi::reset(c) }
            }
            #[no_mangle]
            pub unsafe extern "C" fn fmi2GetReal(
                c: *mut c_void,
                vr: *const u32,
                n: usize,
                value: *mut f64,
            ) -> i32 {
                unsafe { ffi::get_real(c, vr, n, value) }
            }
            #[no_mangle]
            pub unsafe extern "C" fn fmi2GetInteger(
                c: *mut c_void,
                vr: *const u32,
                n: usize,
                value: *mut i32,
            ) -> i32 {
                unsafe { ffi::get_integer(c, vr, n, value) }
            }
            #[no_mangle]
            pub unsafe extern "C" fn fmi2GetBoolean(
                c: *mut c_void,
                _vr: *const u32,
                n: usize,
                _value: *mut i32,
            ) -> i32 {
                unsafe { ffi::no_such_variables(c, n, "Boolean") }
            }
            #[no_mangle]
            pub unsafe extern "C" fn fmi2GetString(
                c: *mut c_void,
                _vr: *const u32,
                n: usize,
                _value: *mut *const c_char,
            ) -> i32 {
                unsafe { ffi::no_such_variables(c, n, "String") }
            }
            #[no_mangle]
            pub unsafe extern "C" fn fmi2SetReal(
                c: *mut c_void,
                vr: *const u32,
                n: usize,
                value: *const f64,
            ) -> i32 {
                unsafe { ffi::set_real(c, vr, n, value) }
            }
            #[no_mangle]
            pub unsafe extern "C" fn fmi2SetInteger(
                c: *mut c_void,
                vr: *const u32,
                n: usize,
                value: *const i32,
            ) -> i32 {
                unsafe { ffi::set_integer(c, vr, n, value) }
            }
            #[no_mangle]
            pub unsafe extern "C" fn fmi2SetBoolean(
                c: *mut c_void,
                _vr: *const u32,
                n: usize,
                _value: *const i32,
            ) -> i32 {
                unsafe { ffi::no_such_variables(c, n, "Boolean") }
            }
            #[no_mangle]
            pub unsafe extern "C" fn fmi2SetString(
                c: *mut c_void,
                _vr: *const u32,
                n: usize,
                _value: *const *const c_char,
            ) -> i32 {
                unsafe { ffi::no_such_variables(c, n, "String") }
            }
            #[no_mangle]
            pub unsafe extern "C" fn fmi2GetFMUstate(
                c: *mut c_void,
                state: *mut *mut c_void,
            ) -> i32 {
                unsafe { ffi::get_fmu_state(c, state) }
            }
            #[no_mangle]
            pub unsafe extern "C" fn fmi2SetFMUstate(c: *mut c_void, state: *mut c_void) -> i32 {
                unsafe { ffi::set_fmu_state(c, state) }
            }
            #[no_mangle]
            pub unsafe extern "C" fn fmi2FreeFMUstate(
                c: *mut c_void,
                state: *mut *mut c_void,
            ) -> i32 {
                unsafe { ffi::free_fmu_state(c, state) }
            }
            #[no_mangle]
            pub unsafe extern "C" fn fmi2SerializedFMUstateSize(
                c: *mut c_void,
                state: *mut c_void,
                size: *mut usize,
            ) -> i32 {
                unsafe { ffi::serialized_fmu_state_size(c, state, size) }
            }
            #[no_mangle]
            pub unsafe extern "C" fn fmi2SerializeFMUstate(
                c: *mut c_void,
                state: *mut c_void,
                bytes: *mut u8,
                size: usize,
            ) -> i32 {
                unsafe { ffi::serialize_fmu_state(c, state, bytes, size) }
            }
            #[no_mangle]
            pub unsafe extern "C" fn fmi2DeSerializeFMUstate(
                c: *mut c_void,
                bytes: *const u8,
                size: usize,
                state: *mut *mut c_void,
            ) -> i32 {
                unsafe { ffi::deserialize_fmu_state(c, bytes, size, state) }
            }
            #[no_mangle]
            pub unsafe extern "C" fn fmi2GetDirectionalDerivative(
                c: *mut c_void,
                _unknown: *const u32,
                _n_unknown: usize,
                _known: *const u32,
                _n_known: usize,
                _dv_known: *const f64,
                _dv_unknown: *mut f64,
            ) -> i32 {
                unsafe { ffi::unsupported(c, "fmi2GetDirectionalDerivative") }
            }
            #[no_mangle]
            pub unsafe extern "C" fn fmi2SetRealInputDerivatives(
                c: *mut c_void,
                _vr: *const u32,
                _n: usize,
                _order: *const i32,
                _value: *const f64,
            ) -> i32 {
                unsafe { ffi::unsupported(c, "fmi2SetRealInputDerivatives") }
            }
            #[no_mangle]
            pub unsafe extern "C" fn fmi2GetRealOutputDerivatives(
                c: *mut c_void,
                _vr: *const u32,
                _n: usize,
                _order: *const i32,
                _value: *mut f64,
            ) -> i32 {
                unsafe { ffi::unsupported(c, "fmi2GetRealOutputDerivatives") }
            }
            #[no_mangle]
            pub unsafe extern "C" fn fmi2DoStep(
                c: *mut c_void,
                t: f64,
                h: f64,
                no_prior: i32,
            ) -> i32 {
                unsafe { ffi::do_step(c, t, h, no_prior) }
            }
            #[no_mangle]
            pub unsafe extern "C" fn fmi2CancelStep(c: *mut c_void) -> i32 {
                unsafe { ffi::unsupported(c, "fmi2CancelStep") }
            }
            #[no_mangle]
            pub unsafe extern "C" fn fmi2GetStatus(
                c: *mut c_void,
                kind: i32,
                value: *mut i32,
            ) -> i32 {
                unsafe { ffi::get_status(c, kind, value) }
            }
            #[no_mangle]
            pub unsafe extern "C" fn fmi2GetRealStatus(
                c: *mut c_void,
                kind: i32,
                value: *mut f64,
            ) -> i32 {
                unsafe { ffi::get_real_status(c, kind, value) }
            }
            #[no_mangle]
            pub unsafe extern "C" fn fmi2GetIntegerStatus(
                c: *mut c_void,
                _kind: i32,
                _value: *mut i32,
            ) -> i32 {
                unsafe { ffi::unsupported(c, "fmi2GetIntegerStatus") }
            }
            #[no_mangle]
            pub unsafe extern "C" fn fmi2GetBooleanStatus(
                c: *mut c_void,
                kind: i32,
                value: *mut i32,
            ) -> i32 {
                unsafe { ffi::get_boolean_status(c, kind, value) }
            }
            #[no_mangle]
            pub unsafe extern "C" fn fmi2GetStringStatus(
                c: *mut c_void,
                _kind: i32,
                _value: *mut *const c_char,
            ) -> i32 {
                unsafe { ffi::unsupported(c, "fmi2GetStringStatus") }
            }
        }
    };
}
