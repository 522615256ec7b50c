//! The FMI 2.0 C interface: each `fmi2…` function of the standard as a
//! Rust function with its C signature, converting arguments and results
//! and calling [`Instance`]. No function unwinds into the importer: each
//! body runs under `catch_unwind`, and a null or unknown component is an
//! error status, never a dereference. [`crate::export_fmu!`] exports them
//! under their C names.
//!
//! Written from the FMI 2.0.4 standard's function signatures; no FMI
//! header or code is copied.

use crate::instance::{Instance, Phase, Saved, Stepped};
use lagc_runtime::model::DynModel;
use std::ffi::{c_char, c_void, CStr, CString};
use std::panic::{catch_unwind, AssertUnwindSafe};

pub type Status = i32;
pub const OK: Status = 0;
pub const WARNING: Status = 1;
pub const DISCARD: Status = 2;
pub const ERROR: Status = 3;
pub const FATAL: Status = 4;

/// `fmi2CallbackLogger`: C-variadic; lagc passes its message through `%s`.
pub type Logger =
    unsafe extern "C" fn(*mut c_void, *const c_char, Status, *const c_char, *const c_char, ...);

/// `fmi2CallbackFunctions`.
#[repr(C)]
pub struct Callbacks {
    pub logger: Option<Logger>,
    pub allocate_memory: Option<unsafe extern "C" fn(usize, usize) -> *mut c_void>,
    pub free_memory: Option<unsafe extern "C" fn(*mut c_void)>,
    pub step_finished: Option<unsafe extern "C" fn(*mut c_void, Status)>,
    pub component_environment: *mut c_void,
}

/// What `fmi2Component` points to.
pub struct Component {
    instance: Instance,
    name: CString,
    logger: Option<Logger>,
    environment: *mut c_void,
    logging: bool,
    /// The time a `stop when` ended the motion, for fmi2GetRealStatus.
    ended_at: Option<f64>,
}

impl Component {
    fn log(&self, status: Status, category: &str, message: &str) {
        let Some(logger) = self.logger else { return };
        if status == OK && !self.logging {
            return;
        }
        let category = CString::new(category).unwrap_or_default();
        let message = CString::new(message.replace('\0', " ")).unwrap_or_default();
        // SAFETY: the importer gave this logger for this environment; the
        // format is a literal `%s` and its one argument a C string.
        unsafe {
            logger(
                self.environment,
                self.name.as_ptr(),
                status,
                category.as_ptr(),
                c"%s".as_ptr(),
                message.as_ptr(),
            );
        }
    }

    /// `Ok` → fmi2OK; `Err` logged under `logStatusError`, fmi2Error.
    fn status(&mut self, result: Result<(), crate::instance::Error>) -> Status {
        match result {
            Ok(()) => OK,
            Err(error) => {
                self.log(ERROR, "logStatusError", &error.0);
                ERROR
            }
        }
    }
}

/// Runs `body` on the component `c`, turning a null component into
/// fmi2Error and a panic into fmi2Fatal (logged when possible).
///
/// # Safety
/// `c` is null or a component from [`instantiate`] not yet freed.
unsafe fn with(c: *mut c_void, body: impl FnOnce(&mut Component) -> Status) -> Status {
    if c.is_null() {
        return ERROR;
    }
    // SAFETY: the caller's contract.
    let component = unsafe { &mut *(c as *mut Component) };
    let pointer = component as *mut Component;
    match catch_unwind(AssertUnwindSafe(|| body(component))) {
        Ok(status) => status,
        Err(_) => {
            // SAFETY: the body is gone; the component is still valid.
            let component = unsafe { &mut *pointer };
            component.instance.phase = Phase::Failed;
            component.log(
                FATAL,
                "logStatusFatal",
                "internal error (a panic) in the FMU",
            );
            FATAL
        }
    }
}

/// A C string argument, or `None` for null or invalid UTF-8.
unsafe fn text<'a>(s: *const c_char) -> Option<&'a str> {
    if s.is_null() {
        return None;
    }
    // SAFETY: a non-null `fmi2String` is a NUL-terminated string.
    unsafe { CStr::from_ptr(s) }.to_str().ok()
}

/// A C array argument as a slice (empty for `n = 0`, `None` for null).
unsafe fn slice<'a, T>(p: *const T, n: usize) -> Option<&'a [T]> {
    if n == 0 {
        return Some(&[]);
    }
    if p.is_null() {
        return None;
    }
    // SAFETY: the importer passes `n` elements.
    Some(unsafe { std::slice::from_raw_parts(p, n) })
}

unsafe fn slice_mut<'a, T>(p: *mut T, n: usize) -> Option<&'a mut [T]> {
    if n == 0 {
        return Some(&mut []);
    }
    if p.is_null() {
        return None;
    }
    // SAFETY: the importer passes room for `n` elements.
    Some(unsafe { std::slice::from_raw_parts_mut(p, n) })
}

pub fn get_types_platform() -> *const c_char {
    c"default".as_ptr()
}

pub fn get_version() -> *const c_char {
    c"2.0".as_ptr()
}

/// `fmi2Instantiate` for the model `prototype` makes.
///
/// # Safety
/// The arguments as the standard defines them.
#[allow(clippy::too_many_arguments)]
pub unsafe fn instantiate(
    prototype: fn() -> Box<dyn DynModel>,
    tunable: &'static [usize],
    name: *const c_char,
    fmu_type: i32,
    guid: *const c_char,
    _resources: *const c_char,
    callbacks: *const Callbacks,
    _visible: i32,
    logging: i32,
) -> *mut c_void {
    let made = catch_unwind(|| {
        // SAFETY: the importer's callbacks, when given, live as long as
        // the instance (the standard requires it).
        let (logger, environment) = match unsafe { callbacks.as_ref() } {
            Some(c) => (c.logger, c.component_environment),
            None => (None, std::ptr::null_mut()),
        };
        let model = prototype();
        let component = Component {
            name: CString::new(unsafe { text(name) }.unwrap_or("")).unwrap_or_default(),
            instance: Instance::new(model).with_tunable(tunable),
            logger,
            environment,
            logging: logging != 0,
            ended_at: None,
        };
        let hash = component.instance_hash();
        let problem = if fmu_type != 1 {
            Some("this FMU is for co-simulation only (fmi2CoSimulation)".to_string())
        } else if unsafe { text(guid) } != Some(hash) {
            Some(format!(
                "the GUID {:?} is not this model's ({hash:?})",
                unsafe { text(guid) }.unwrap_or("")
            ))
        } else {
            None
        };
        if let Some(problem) = problem {
            component.log(ERROR, "logStatusError", &problem);
            return std::ptr::null_mut();
        }
        Box::into_raw(Box::new(component)) as *mut c_void
    });
    made.unwrap_or(std::ptr::null_mut())
}

impl Component {
    fn instance_hash(&self) -> &'static str {
        self.instance.source_hash()
    }
}

/// # Safety
/// `c` is null or a live component; it is not used afterwards.
pub unsafe fn free_instance(c: *mut c_void) {
    if !c.is_null() {
        // SAFETY: made by `instantiate` with `Box::into_raw`.
        let _ = catch_unwind(|| drop(unsafe { Box::from_raw(c as *mut Component) }));
    }
}

/// # Safety
/// `c` as in [`with`].
pub unsafe fn set_debug_logging(c: *mut c_void, on: i32) -> Status {
    unsafe {
        with(c, |comp| {
            comp.logging = on != 0;
            OK
        })
    }
}

/// # Safety
/// `c` as in [`with`].
pub unsafe fn setup_experiment(
    c: *mut c_void,
    tolerance_defined: i32,
    tolerance: f64,
    start: f64,
    stop_defined: i32,
    stop: f64,
) -> Status {
    unsafe {
        with(c, |comp| {
            let result = comp.instance.setup(
                (tolerance_defined != 0).then_some(tolerance),
                start,
                (stop_defined != 0).then_some(stop),
            );
            comp.status(result)
        })
    }
}

/// # Safety
/// `c` as in [`with`].
pub unsafe fn enter_initialization_mode(c: *mut c_void) -> Status {
    unsafe {
        with(c, |comp| {
            let result = comp.instance.enter_initialization();
            comp.status(result)
        })
    }
}

/// # Safety
/// `c` as in [`with`].
pub unsafe fn exit_initialization_mode(c: *mut c_void) -> Status {
    unsafe {
        with(c, |comp| {
            let result = comp.instance.exit_initialization();
            if result.is_err() {
                comp.instance.phase = Phase::Failed;
            }
            comp.status(result)
        })
    }
}

/// # Safety
/// `c` as in [`with`].
pub unsafe fn terminate(c: *mut c_void) -> Status {
    unsafe {
        with(c, |comp| {
            // The integrator's work, for the log (with debug logging on).
            if let Some(outcome) = comp.instance.outcome() {
                let stats = outcome.report.stats;
                let message = format!(
                    "{}: {} steps (+{} rejected), {} right-side evaluations, {} events",
                    outcome.report.method,
                    stats.accepted_steps,
                    stats.rejected_steps,
                    stats.rhs_evaluations,
                    outcome.events
                );
                comp.log(OK, "logEvents", &message);
            }
            let result = comp.instance.terminate();
            comp.status(result)
        })
    }
}

/// # Safety
/// `c` as in [`with`].
pub unsafe fn reset(c: *mut c_void) -> Status {
    unsafe {
        with(c, |comp| {
            comp.instance.reset();
            comp.ended_at = None;
            OK
        })
    }
}

/// # Safety
/// `c` as in [`with`]; `vr` and `value` hold `n` elements.
pub unsafe fn get_real(c: *mut c_void, vr: *const u32, n: usize, value: *mut f64) -> Status {
    unsafe {
        with(c, |comp| {
            let (Some(vr), Some(value)) = (slice(vr, n), slice_mut(value, n)) else {
                return comp.status(Err(crate::instance::Error("a null array".into())));
            };
            for (r, v) in vr.iter().zip(value.iter_mut()) {
                match comp.instance.get_real(*r) {
                    Ok(x) => *v = x,
                    Err(e) => return comp.status(Err(e)),
                }
            }
            OK
        })
    }
}

/// # Safety
/// `c` as in [`with`]; `vr` and `value` hold `n` elements.
pub unsafe fn set_real(c: *mut c_void, vr: *const u32, n: usize, value: *const f64) -> Status {
    unsafe {
        with(c, |comp| {
            let (Some(vr), Some(value)) = (slice(vr, n), slice(value, n)) else {
                return comp.status(Err(crate::instance::Error("a null array".into())));
            };
            for (r, v) in vr.iter().zip(value) {
                if let Err(e) = comp.instance.set_real(*r, *v) {
                    return comp.status(Err(e));
                }
            }
            OK
        })
    }
}

/// # Safety
/// `c` as in [`with`]; `vr` and `value` hold `n` elements.
pub unsafe fn get_integer(c: *mut c_void, vr: *const u32, n: usize, value: *mut i32) -> Status {
    unsafe {
        with(c, |comp| {
            let (Some(vr), Some(value)) = (slice(vr, n), slice_mut(value, n)) else {
                return comp.status(Err(crate::instance::Error("a null array".into())));
            };
            for (r, v) in vr.iter().zip(value.iter_mut()) {
                match comp.instance.get_integer(*r) {
                    Ok(x) => *v = x,
                    Err(e) => return comp.status(Err(e)),
                }
            }
            OK
        })
    }
}

/// # Safety
/// `c` as in [`with`]; `vr` and `value` hold `n` elements.
pub unsafe fn set_integer(c: *mut c_void, vr: *const u32, n: usize, value: *const i32) -> Status {
    unsafe {
        with(c, |comp| {
            let (Some(vr), Some(value)) = (slice(vr, n), slice(value, n)) else {
                return comp.status(Err(crate::instance::Error("a null array".into())));
            };
            for (r, v) in vr.iter().zip(value) {
                if let Err(e) = comp.instance.set_integer(*r, *v) {
                    return comp.status(Err(e));
                }
            }
            OK
        })
    }
}

/// Boolean and String variables: the model has none, so any
/// reference is unknown (none at all is fine).
///
/// # Safety
/// `c` as in [`with`].
pub unsafe fn no_such_variables(c: *mut c_void, n: usize, kind: &str) -> Status {
    unsafe {
        with(c, |comp| {
            if n == 0 {
                return OK;
            }
            comp.status(Err(crate::instance::Error(format!(
                "the model has no {kind} variables"
            ))))
        })
    }
}

/// # Safety
/// `c` as in [`with`].
pub unsafe fn do_step(c: *mut c_void, t: f64, h: f64, _no_prior: i32) -> Status {
    unsafe {
        with(c, |comp| match comp.instance.do_step(t, h) {
            Ok(Stepped::Done) => OK,
            Ok(Stepped::Ended(at)) => {
                comp.ended_at = Some(at);
                comp.log(
                    OK,
                    "logEvents",
                    &format!("`stop when` ended the motion at t = {at}"),
                );
                DISCARD
            }
            Err(e) => {
                comp.instance.phase = Phase::Failed;
                comp.status(Err(e))
            }
        })
    }
}

/// Status kinds of fmi2Get…Status.
const DO_STEP_STATUS: i32 = 0;
const LAST_SUCCESSFUL_TIME: i32 = 2;
const TERMINATED: i32 = 3;

/// # Safety
/// `c` as in [`with`]; `value` points to one value.
pub unsafe fn get_status(c: *mut c_void, kind: i32, value: *mut Status) -> Status {
    unsafe {
        with(c, |comp| match (kind, value.as_mut()) {
            (DO_STEP_STATUS, Some(v)) => {
                *v = if comp.ended_at.is_some() { DISCARD } else { OK };
                OK
            }
            _ => DISCARD,
        })
    }
}

/// # Safety
/// `c` as in [`with`]; `value` points to one value.
pub unsafe fn get_real_status(c: *mut c_void, kind: i32, value: *mut f64) -> Status {
    unsafe {
        with(c, |comp| match (kind, value.as_mut()) {
            (LAST_SUCCESSFUL_TIME, Some(v)) => {
                *v = comp.ended_at.unwrap_or(comp.instance.t);
                OK
            }
            _ => DISCARD,
        })
    }
}

/// # Safety
/// `c` as in [`with`]; `value` points to one value.
pub unsafe fn get_boolean_status(c: *mut c_void, kind: i32, value: *mut i32) -> Status {
    unsafe {
        with(c, |comp| match (kind, value.as_mut()) {
            (TERMINATED, Some(v)) => {
                *v = i32::from(comp.ended_at.is_some());
                OK
            }
            _ => DISCARD,
        })
    }
}

/// What the FMU does not offer (its modelDescription says so): an error
/// naming the call.
///
/// # Safety
/// `c` as in [`with`].
pub unsafe fn unsupported(c: *mut c_void, call: &str) -> Status {
    unsafe {
        with(c, |comp| {
            comp.status(Err(crate::instance::Error(format!(
                "{call} is not supported by this FMU"
            ))))
        })
    }
}

/// # Safety
/// `c` as in [`with`]; `state` points to one `fmi2FMUstate`.
pub unsafe fn get_fmu_state(c: *mut c_void, state: *mut *mut c_void) -> Status {
    unsafe {
        with(c, |comp| {
            let Some(slot) = state.as_mut() else {
                return ERROR;
            };
            let saved = comp.instance.save();
            let saved = Box::new((saved, comp.ended_at));
            if !slot.is_null() {
                drop(Box::from_raw(*slot as *mut (Saved, Option<f64>)));
            }
            *slot = Box::into_raw(saved) as *mut c_void;
            OK
        })
    }
}

/// # Safety
/// `c` as in [`with`]; `state` from [`get_fmu_state`].
pub unsafe fn set_fmu_state(c: *mut c_void, state: *mut c_void) -> Status {
    unsafe {
        with(c, |comp| {
            let Some((saved, ended_at)) = (state as *const (Saved, Option<f64>)).as_ref() else {
                return ERROR;
            };
            let restored = comp.instance.restore(saved);
            if restored.is_ok() {
                comp.ended_at = *ended_at;
            }
            comp.status(restored)
        })
    }
}

/// # Safety
/// `c` as in [`with`]; `state` points to a state from [`get_fmu_state`]
/// or null.
pub unsafe fn free_fmu_state(c: *mut c_void, state: *mut *mut c_void) -> Status {
    unsafe {
        with(c, |_| {
            if let Some(slot) = state.as_mut() {
                if !slot.is_null() {
                    drop(Box::from_raw(*slot as *mut (Saved, Option<f64>)));
                    *slot = std::ptr::null_mut();
                }
            }
            OK
        })
    }
}

/// # Safety
/// `c` as in [`with`]; `state` from [`get_fmu_state`]; `size` points to
/// one `size_t`.
pub unsafe fn serialized_fmu_state_size(
    c: *mut c_void,
    state: *mut c_void,
    size: *mut usize,
) -> Status {
    unsafe {
        with(c, |_| {
            let (Some((saved, ended_at)), Some(size)) = (
                (state as *const (Saved, Option<f64>)).as_ref(),
                size.as_mut(),
            ) else {
                return ERROR;
            };
            *size = saved.to_bytes(*ended_at).len();
            OK
        })
    }
}

/// # Safety
/// `c` as in [`with`]; `state` from [`get_fmu_state`]; `bytes` points to
/// `size` writable bytes.
pub unsafe fn serialize_fmu_state(
    c: *mut c_void,
    state: *mut c_void,
    bytes: *mut u8,
    size: usize,
) -> Status {
    unsafe {
        with(c, |comp| {
            let Some((saved, ended_at)) = (state as *const (Saved, Option<f64>)).as_ref() else {
                return ERROR;
            };
            let serial = saved.to_bytes(*ended_at);
            if bytes.is_null() || size < serial.len() {
                return comp.status(Err(crate::instance::Error(format!(
                    "fmi2SerializeFMUstate: {size} bytes given, the state takes {} \
                     (fmi2SerializedFMUstateSize)",
                    serial.len()
                ))));
            }
            std::ptr::copy_nonoverlapping(serial.as_ptr(), bytes, serial.len());
            OK
        })
    }
}

/// # Safety
/// `c` as in [`with`]; `bytes` points to `size` readable bytes; `state`
/// points to one `fmi2FMUstate` (a new state is made there).
pub unsafe fn deserialize_fmu_state(
    c: *mut c_void,
    bytes: *const u8,
    size: usize,
    state: *mut *mut c_void,
) -> Status {
    unsafe {
        with(c, |comp| {
            let Some(slot) = state.as_mut() else {
                return ERROR;
            };
            if bytes.is_null() {
                return ERROR;
            }
            let serial = std::slice::from_raw_parts(bytes, size);
            match Saved::from_bytes(serial, &comp.instance) {
                Ok(saved) => {
                    if !slot.is_null() {
                        drop(Box::from_raw(*slot as *mut (Saved, Option<f64>)));
                    }
                    *slot = Box::into_raw(Box::new(saved)) as *mut c_void;
                    OK
                }
                Err(error) => comp.status(Err(error)),
            }
        })
    }
}
