//! The FMI 2.0 Co-Simulation C interface: the 34 exported `fmi2*` functions, each checked
//! against `fmi-sys`'s function type at compile time. All `unsafe` code of the crate lives
//! here: pointer checks, C strings, the variadic logger (always called with "%s"), and a
//! `catch_unwind` around every body so that nothing unwinds into the host. Behaviour lives
//! in [`crate::instance`].

use std::ffi::{CStr, CString, c_char};
use std::panic::{AssertUnwindSafe, catch_unwind};
use std::path::PathBuf;

use fmi_sys::fmi2::*;
use model_description::VarType;

use crate::error::{FusionError, Result};
use crate::instance::{Call, Instance, Logger, Status};
use crate::params::Value;

/// What an `fmi2Component` points to.
struct Component {
    instance: Instance,
    /// Strings handed out by the last fmi2GetString (valid until the next call).
    strings: Vec<CString>,
}

fn code(s: Status) -> fmi2Status {
    match s {
        Status::Ok => fmi2Status_fmi2OK,
        Status::Warning => fmi2Status_fmi2Warning,
        Status::Discard => fmi2Status_fmi2Discard,
        Status::Error => fmi2Status_fmi2Error,
        Status::Fatal => fmi2Status_fmi2Fatal,
    }
}

std::thread_local! {
    /// The message and place of the last panic on this thread, for the logger.
    static LAST_PANIC: std::cell::RefCell<Option<String>> = const { std::cell::RefCell::new(None) };
}

/// Replaces the default panic hook, which prints to the host's stderr, by one that keeps
/// the message for the instance's logger (the FMU's copy of the Rust runtime is its own:
/// this hook sees the FMU's panics only). Idempotent.
fn quiet_panics() {
    static ONCE: std::sync::Once = std::sync::Once::new();
    ONCE.call_once(|| {
        std::panic::set_hook(Box::new(|info| {
            let place = info
                .location()
                .map(|l| format!(" at {}:{}", l.file(), l.line()))
                .unwrap_or_default();
            let text = format!("{}{place}", panic_text(info.payload()));
            LAST_PANIC.with(|p| *p.borrow_mut() = Some(text));
        }));
    });
}

/// The text of a caught panic: what the hook kept (with its place), else its payload.
fn caught_panic(p: &(dyn std::any::Any + Send)) -> String {
    LAST_PANIC
        .with(|last| last.borrow_mut().take())
        .unwrap_or_else(|| panic_text(p))
}

/// The text of a panic's payload.
fn panic_text(p: &(dyn std::any::Any + Send)) -> String {
    p.downcast_ref::<&str>()
        .map(|s| s.to_string())
        .or_else(|| p.downcast_ref::<String>().cloned())
        .unwrap_or_else(|| "unknown panic".into())
}

/// Runs `body` on the component behind `c` for `call`: null check, state mask, panic
/// barrier, status escalation.
///
/// # Safety
/// `c` is null or a pointer returned by [`fmi2Instantiate`] and not yet freed.
unsafe fn with(
    c: fmi2Component,
    call: Call,
    body: impl FnOnce(&mut Component) -> Result<Status>,
) -> fmi2Status {
    if c.is_null() {
        return fmi2Status_fmi2Error;
    }
    // SAFETY: by the contract above, `c` came from Box::into_raw in fmi2Instantiate.
    let comp = unsafe { &mut *(c as *mut Component) };
    let outcome = catch_unwind(AssertUnwindSafe(|| {
        comp.instance.log(Status::Ok, "logCalls", call.name());
        let r = comp.instance.check(call).and_then(|()| body(comp));
        comp.instance.finish(call, r)
    }));
    match outcome {
        Ok(s) => code(s),
        Err(p) => {
            let msg = format!(
                "{}: internal error (panic: {}); the instance is in the Error state",
                call.name(),
                caught_panic(&*p)
            );
            let _ = catch_unwind(AssertUnwindSafe(|| {
                comp.instance.poison();
                comp.instance.log(Status::Error, "logStatusError", &msg);
            }));
            fmi2Status_fmi2Error
        }
    }
}

/// A slice from a C array, empty for n = 0; an error for a null pointer with n > 0.
///
/// # Safety
/// `p` is null or points to `n` valid values.
unsafe fn slice<'a, T>(p: *const T, n: usize, what: &str) -> Result<&'a [T]> {
    if n == 0 {
        Ok(&[])
    } else if p.is_null() {
        Err(FusionError::BadArgument(format!(
            "{what} is a null pointer"
        )))
    } else {
        // SAFETY: non-null and, by the contract above, n valid values.
        Ok(unsafe { std::slice::from_raw_parts(p, n) })
    }
}

/// A mutable slice from a C array (see [`slice`]).
///
/// # Safety
/// `p` is null or points to `n` writable values.
unsafe fn slice_mut<'a, T>(p: *mut T, n: usize, what: &str) -> Result<&'a mut [T]> {
    if n == 0 {
        Ok(&mut [])
    } else if p.is_null() {
        Err(FusionError::BadArgument(format!(
            "{what} is a null pointer"
        )))
    } else {
        // SAFETY: non-null and, by the contract above, n writable values.
        Ok(unsafe { std::slice::from_raw_parts_mut(p, n) })
    }
}

/// A Rust string from a C string; an error for null or non-UTF-8.
///
/// # Safety
/// `p` is null or a NUL-terminated string.
unsafe fn text<'a>(p: *const c_char, what: &str) -> Result<&'a str> {
    if p.is_null() {
        return Err(FusionError::BadArgument(format!(
            "{what} is a null pointer"
        )));
    }
    // SAFETY: non-null and NUL-terminated by the contract above.
    unsafe { CStr::from_ptr(p) }
        .to_str()
        .map_err(|_| FusionError::BadArgument(format!("{what} is not UTF-8")))
}

/// The resources folder from the location an importer passes (file URLs in their various
/// spellings; null and unparsable give none).
fn resources_dir(location: Option<&str>) -> Option<PathBuf> {
    let loc = location?.trim();
    if loc.is_empty() {
        return None;
    }
    match url::Url::parse(loc) {
        Ok(u) if u.scheme() == "file" => u.to_file_path().ok(),
        Ok(_) => None,
        Err(_) => Some(PathBuf::from(loc)).filter(|p| p.is_absolute()),
    }
}

// ---- Inquiry ---------------------------------------------------------------------------

/// fmi2GetTypesPlatform: "default".
#[unsafe(no_mangle)]
pub extern "C" fn fmi2GetTypesPlatform() -> *const c_char {
    c"default".as_ptr()
}

/// fmi2GetVersion: "2.0".
#[unsafe(no_mangle)]
pub extern "C" fn fmi2GetVersion() -> *const c_char {
    c"2.0".as_ptr()
}

// ---- Creation and destruction ----------------------------------------------------------

/// fmi2Instantiate: a new Co-Simulation instance; null when the GUID or type is wrong.
///
/// # Safety
/// Pointers as FMI 2.0 specifies: C strings or null, `functions` null or valid.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn fmi2Instantiate(
    instance_name: fmi2String,
    fmu_type: fmi2Type,
    fmu_guid: fmi2String,
    fmu_resource_location: fmi2String,
    functions: *const fmi2CallbackFunctions,
    _visible: fmi2Boolean,
    logging_on: fmi2Boolean,
) -> fmi2Component {
    if functions.is_null() {
        return std::ptr::null_mut();
    }
    // SAFETY: non-null, and an importer passes a valid struct.
    let cb = unsafe { *functions };
    quiet_panics();
    let outcome = catch_unwind(AssertUnwindSafe(|| {
        // SAFETY: C strings or null by the contract above.
        let name = unsafe { text(instance_name, "instanceName") }
            .unwrap_or("FtFusion")
            .to_owned();
        let c_name = CString::new(name.clone()).unwrap_or_default();
        let (log_fn, env) = (cb.logger, cb.componentEnvironment);
        let logger: Logger = Box::new(move |status, category, msg| {
            if let Some(f) = log_fn {
                let category = CString::new(category).unwrap_or_default();
                let msg = CString::new(msg.replace('\0', " ")).unwrap_or_default();
                // SAFETY: the importer's logger, called with its environment, the instance
                // name, a category and the message behind a fixed "%s" format.
                unsafe {
                    f(
                        env,
                        c_name.as_ptr(),
                        code(status),
                        category.as_ptr(),
                        c"%s".as_ptr(),
                        msg.as_ptr(),
                    )
                };
            }
        });
        // SAFETY: C strings or null by the contract above.
        let location = unsafe { text(fmu_resource_location, "fmuResourceLocation") }.ok();
        let instance = Instance::new(&name, resources_dir(location), logger, logging_on != 0);
        if fmu_type != fmi2Type_fmi2CoSimulation {
            instance.log(
                Status::Error,
                "logStatusError",
                "fmi2Instantiate: FtFusion is a Co-Simulation FMU only",
            );
            return None;
        }
        // SAFETY: C string or null by the contract above.
        let guid = unsafe { text(fmu_guid, "fmuGUID") }.unwrap_or("");
        if guid != model_description::guid() {
            instance.log(
                Status::Error,
                "logStatusError",
                &format!(
                    "fmi2Instantiate: GUID {guid} does not match this FMU's {} (modelDescription.xml and binary differ)",
                    model_description::guid()
                ),
            );
            return None;
        }
        if location.is_some() && resources_dir(location).is_none() {
            instance.log(
                Status::Warning,
                "logStatusWarning",
                &format!("fmi2Instantiate: resource location {location:?} is not a file URL: relative map names will fail"),
            );
        }
        Some(Box::into_raw(Box::new(Component {
            instance,
            strings: Vec::new(),
        })) as fmi2Component)
    }));
    outcome.ok().flatten().unwrap_or(std::ptr::null_mut())
}

/// fmi2FreeInstance.
///
/// # Safety
/// `c` is null or a live pointer from [`fmi2Instantiate`]; it is invalid afterwards.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn fmi2FreeInstance(c: fmi2Component) {
    if c.is_null() {
        return;
    }
    // SAFETY: `c` came from Box::into_raw in fmi2Instantiate and is freed once.
    let comp = unsafe { Box::from_raw(c as *mut Component) };
    let _ = catch_unwind(AssertUnwindSafe(move || {
        drop(comp);
        crate::shared::release_unused();
    }));
}

/// fmi2SetDebugLogging.
///
/// # Safety
/// `c` as for [`fmi2FreeInstance`]; `categories` holds `n` C strings.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn fmi2SetDebugLogging(
    c: fmi2Component,
    logging_on: fmi2Boolean,
    n: usize,
    categories: *const fmi2String,
) -> fmi2Status {
    // SAFETY: the caller's contract.
    unsafe {
        with(c, Call::SetDebugLogging, |comp| {
            let cats = slice(categories, n, "categories")?
                .iter()
                .map(|&p| text(p, "category").map(str::to_owned))
                .collect::<Result<Vec<_>>>()?;
            comp.instance.set_debug_logging(logging_on != 0, &cats)
        })
    }
}

// ---- Initialization, termination, reset -----------------------------------------------

/// fmi2SetupExperiment.
///
/// # Safety
/// `c` as for [`fmi2FreeInstance`].
#[unsafe(no_mangle)]
pub unsafe extern "C" fn fmi2SetupExperiment(
    c: fmi2Component,
    _tolerance_defined: fmi2Boolean,
    _tolerance: fmi2Real,
    start_time: fmi2Real,
    _stop_time_defined: fmi2Boolean,
    _stop_time: fmi2Real,
) -> fmi2Status {
    // SAFETY: the caller's contract.
    unsafe {
        with(c, Call::SetupExperiment, |comp| {
            comp.instance.setup_experiment(start_time)
        })
    }
}

/// fmi2EnterInitializationMode.
///
/// # Safety
/// `c` as for [`fmi2FreeInstance`].
#[unsafe(no_mangle)]
pub unsafe extern "C" fn fmi2EnterInitializationMode(c: fmi2Component) -> fmi2Status {
    // SAFETY: the caller's contract.
    unsafe {
        with(c, Call::EnterInitializationMode, |comp| {
            comp.instance.enter_initialization_mode()
        })
    }
}

/// fmi2ExitInitializationMode: checks parameters, loads the map, spreads the particles.
///
/// # Safety
/// `c` as for [`fmi2FreeInstance`].
#[unsafe(no_mangle)]
pub unsafe extern "C" fn fmi2ExitInitializationMode(c: fmi2Component) -> fmi2Status {
    // SAFETY: the caller's contract.
    unsafe {
        with(c, Call::ExitInitializationMode, |comp| {
            comp.instance.exit_initialization_mode()
        })
    }
}

/// fmi2Terminate.
///
/// # Safety
/// `c` as for [`fmi2FreeInstance`].
#[unsafe(no_mangle)]
pub unsafe extern "C" fn fmi2Terminate(c: fmi2Component) -> fmi2Status {
    // SAFETY: the caller's contract.
    unsafe { with(c, Call::Terminate, |comp| comp.instance.terminate()) }
}

/// fmi2Reset.
///
/// # Safety
/// `c` as for [`fmi2FreeInstance`].
#[unsafe(no_mangle)]
pub unsafe extern "C" fn fmi2Reset(c: fmi2Component) -> fmi2Status {
    // SAFETY: the caller's contract.
    unsafe { with(c, Call::Reset, |comp| comp.instance.reset()) }
}

// ---- Getting and setting variables -----------------------------------------------------

/// Reads `nvr` values of type `ty` into `value`, converting each with `read`.
///
/// # Safety
/// `c` as for [`fmi2FreeInstance`]; `vr` and `value` hold `nvr` elements.
unsafe fn get<T>(
    c: fmi2Component,
    ty: VarType,
    name: &'static str,
    vr: *const fmi2ValueReference,
    nvr: usize,
    value: *mut T,
    read: impl Fn(&Value) -> T,
) -> fmi2Status {
    // SAFETY: the caller's contract.
    unsafe {
        with(c, Call::Get(name), |comp| {
            let vrs = slice(vr, nvr, "vr")?;
            let out = slice_mut(value, nvr, "value")?;
            comp.instance.get(ty, vrs, out, read)
        })
    }
}

/// Writes `nvr` values of type `ty`, converting each with `conv`.
///
/// # Safety
/// `c` as for [`fmi2FreeInstance`]; `vr` and `value` hold `nvr` elements.
unsafe fn set<T: Copy>(
    c: fmi2Component,
    ty: VarType,
    name: &'static str,
    vr: *const fmi2ValueReference,
    nvr: usize,
    value: *const T,
    conv: impl Fn(T) -> Result<Value>,
) -> fmi2Status {
    // SAFETY: the caller's contract.
    unsafe {
        with(c, Call::Set(name), |comp| {
            let vrs = slice(vr, nvr, "vr")?;
            let values = slice(value, nvr, "value")?
                .iter()
                .map(|&v| conv(v))
                .collect::<Result<Vec<_>>>()?;
            comp.instance.set(ty, vrs, values)
        })
    }
}

/// fmi2GetReal.
///
/// # Safety
/// `c` as for [`fmi2FreeInstance`]; `vr` and `value` hold `nvr` elements.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn fmi2GetReal(
    c: fmi2Component,
    vr: *const fmi2ValueReference,
    nvr: usize,
    value: *mut fmi2Real,
) -> fmi2Status {
    // SAFETY: the caller's contract.
    unsafe {
        get(
            c,
            VarType::Real,
            "fmi2GetReal",
            vr,
            nvr,
            value,
            |v| match v {
                Value::Real(x) => *x,
                _ => 0.0,
            },
        )
    }
}

/// fmi2GetInteger.
///
/// # Safety
/// `c` as for [`fmi2FreeInstance`]; `vr` and `value` hold `nvr` elements.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn fmi2GetInteger(
    c: fmi2Component,
    vr: *const fmi2ValueReference,
    nvr: usize,
    value: *mut fmi2Integer,
) -> fmi2Status {
    // SAFETY: the caller's contract.
    unsafe {
        get(
            c,
            VarType::Integer,
            "fmi2GetInteger",
            vr,
            nvr,
            value,
            |v| match v {
                Value::Integer(x) => *x,
                _ => 0,
            },
        )
    }
}

/// fmi2GetBoolean.
///
/// # Safety
/// `c` as for [`fmi2FreeInstance`]; `vr` and `value` hold `nvr` elements.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn fmi2GetBoolean(
    c: fmi2Component,
    vr: *const fmi2ValueReference,
    nvr: usize,
    value: *mut fmi2Boolean,
) -> fmi2Status {
    // SAFETY: the caller's contract.
    unsafe {
        get(c, VarType::Boolean, "fmi2GetBoolean", vr, nvr, value, |v| {
            matches!(v, Value::Boolean(true)) as fmi2Boolean
        })
    }
}

/// fmi2GetString: the strings stay valid until the next fmi2GetString on the instance.
///
/// # Safety
/// `c` as for [`fmi2FreeInstance`]; `vr` and `value` hold `nvr` elements.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn fmi2GetString(
    c: fmi2Component,
    vr: *const fmi2ValueReference,
    nvr: usize,
    value: *mut fmi2String,
) -> fmi2Status {
    // SAFETY: the caller's contract.
    unsafe {
        with(c, Call::Get("fmi2GetString"), |comp| {
            let vrs = slice(vr, nvr, "vr")?;
            let out = slice_mut(value, nvr, "value")?;
            let mut texts = vec![String::new(); nvr];
            let status = comp
                .instance
                .get(VarType::String, vrs, &mut texts, |v| match v {
                    Value::String(s) => s.clone(),
                    _ => String::new(),
                })?;
            comp.strings = texts
                .into_iter()
                .map(|s| CString::new(s).unwrap_or_default())
                .collect();
            for (o, s) in out.iter_mut().zip(&comp.strings) {
                *o = s.as_ptr();
            }
            Ok(status)
        })
    }
}

/// fmi2SetReal.
///
/// # Safety
/// `c` as for [`fmi2FreeInstance`]; `vr` and `value` hold `nvr` elements.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn fmi2SetReal(
    c: fmi2Component,
    vr: *const fmi2ValueReference,
    nvr: usize,
    value: *const fmi2Real,
) -> fmi2Status {
    // SAFETY: the caller's contract.
    unsafe {
        set(c, VarType::Real, "fmi2SetReal", vr, nvr, value, |x| {
            Ok(Value::Real(x))
        })
    }
}

/// fmi2SetInteger.
///
/// # Safety
/// `c` as for [`fmi2FreeInstance`]; `vr` and `value` hold `nvr` elements.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn fmi2SetInteger(
    c: fmi2Component,
    vr: *const fmi2ValueReference,
    nvr: usize,
    value: *const fmi2Integer,
) -> fmi2Status {
    // SAFETY: the caller's contract.
    unsafe {
        set(c, VarType::Integer, "fmi2SetInteger", vr, nvr, value, |x| {
            Ok(Value::Integer(x))
        })
    }
}

/// fmi2SetBoolean.
///
/// # Safety
/// `c` as for [`fmi2FreeInstance`]; `vr` and `value` hold `nvr` elements.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn fmi2SetBoolean(
    c: fmi2Component,
    vr: *const fmi2ValueReference,
    nvr: usize,
    value: *const fmi2Boolean,
) -> fmi2Status {
    // SAFETY: the caller's contract.
    unsafe {
        set(c, VarType::Boolean, "fmi2SetBoolean", vr, nvr, value, |x| {
            Ok(Value::Boolean(x != 0))
        })
    }
}

/// fmi2SetString.
///
/// # Safety
/// `c` as for [`fmi2FreeInstance`]; `vr` and `value` hold `nvr` elements, each a C string.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn fmi2SetString(
    c: fmi2Component,
    vr: *const fmi2ValueReference,
    nvr: usize,
    value: *const fmi2String,
) -> fmi2Status {
    // SAFETY: the caller's contract.
    unsafe {
        set(c, VarType::String, "fmi2SetString", vr, nvr, value, |p| {
            Ok(Value::String(text(p, "value")?.to_owned()))
        })
    }
}

// ---- FMU state -------------------------------------------------------------------------

/// The saved state behind an `fmi2FMUstate`: the instance's state bytes.
type Saved = Vec<u8>;

/// fmi2GetFMUstate: allocates a state when `*state` is null, else overwrites it.
///
/// # Safety
/// `c` as for [`fmi2FreeInstance`]; `state` points to null or to a state of this FMU.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn fmi2GetFMUstate(c: fmi2Component, state: *mut fmi2FMUstate) -> fmi2Status {
    // SAFETY: the caller's contract.
    unsafe {
        with(c, Call::State("fmi2GetFMUstate"), |comp| {
            if state.is_null() {
                return Err(FusionError::BadArgument(
                    "FMUstate is a null pointer".into(),
                ));
            }
            let bytes = comp.instance.save_state()?;
            if (*state).is_null() {
                *state = Box::into_raw(Box::new(bytes)) as fmi2FMUstate;
            } else {
                *(*state as *mut Saved) = bytes;
            }
            Ok(Status::Ok)
        })
    }
}

/// fmi2SetFMUstate.
///
/// # Safety
/// `c` as for [`fmi2FreeInstance`]; `state` null or a state of this FMU.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn fmi2SetFMUstate(c: fmi2Component, state: fmi2FMUstate) -> fmi2Status {
    // SAFETY: the caller's contract.
    unsafe {
        with(c, Call::State("fmi2SetFMUstate"), |comp| {
            if state.is_null() {
                return Err(FusionError::BadArgument(
                    "FMUstate is a null pointer".into(),
                ));
            }
            comp.instance.restore_state(&*(state as *const Saved))
        })
    }
}

/// fmi2FreeFMUstate: frees the state and sets `*state` to null.
///
/// # Safety
/// `c` as for [`fmi2FreeInstance`]; `state` null or pointing to null or a state of this FMU.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn fmi2FreeFMUstate(
    c: fmi2Component,
    state: *mut fmi2FMUstate,
) -> fmi2Status {
    // SAFETY: the caller's contract.
    unsafe {
        with(c, Call::State("fmi2FreeFMUstate"), |_| {
            if !state.is_null() && !(*state).is_null() {
                drop(Box::from_raw(*state as *mut Saved));
                *state = std::ptr::null_mut();
            }
            Ok(Status::Ok)
        })
    }
}

/// fmi2SerializedFMUstateSize.
///
/// # Safety
/// `c` as for [`fmi2FreeInstance`]; `state` a state of this FMU; `size` writable.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn fmi2SerializedFMUstateSize(
    c: fmi2Component,
    state: fmi2FMUstate,
    size: *mut usize,
) -> fmi2Status {
    // SAFETY: the caller's contract.
    unsafe {
        with(c, Call::State("fmi2SerializedFMUstateSize"), |_| {
            if state.is_null() || size.is_null() {
                return Err(FusionError::BadArgument(
                    "FMUstate or size is a null pointer".into(),
                ));
            }
            *size = (*(state as *const Saved)).len();
            Ok(Status::Ok)
        })
    }
}

/// fmi2SerializeFMUstate: copies the state's bytes into `bytes` (exactly `size` of them).
///
/// # Safety
/// `c` as for [`fmi2FreeInstance`]; `state` a state of this FMU; `bytes` holds `size` bytes.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn fmi2SerializeFMUstate(
    c: fmi2Component,
    state: fmi2FMUstate,
    bytes: *mut fmi2Byte,
    size: usize,
) -> fmi2Status {
    // SAFETY: the caller's contract.
    unsafe {
        with(c, Call::State("fmi2SerializeFMUstate"), |_| {
            if state.is_null() {
                return Err(FusionError::BadArgument(
                    "FMUstate is a null pointer".into(),
                ));
            }
            let saved = &*(state as *const Saved);
            if size != saved.len() {
                return Err(FusionError::BadArgument(format!(
                    "size {size}, the state has {} bytes",
                    saved.len()
                )));
            }
            slice_mut(bytes as *mut u8, size, "serializedState")?.copy_from_slice(saved);
            Ok(Status::Ok)
        })
    }
}

/// fmi2DeSerializeFMUstate: a new state from bytes; refuses bytes that are not an
/// FtFusion state of this interface.
///
/// # Safety
/// `c` as for [`fmi2FreeInstance`]; `bytes` holds `size` bytes; `state` writable.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn fmi2DeSerializeFMUstate(
    c: fmi2Component,
    bytes: *const fmi2Byte,
    size: usize,
    state: *mut fmi2FMUstate,
) -> fmi2Status {
    // SAFETY: the caller's contract.
    unsafe {
        with(c, Call::State("fmi2DeSerializeFMUstate"), |_| {
            if state.is_null() {
                return Err(FusionError::BadArgument(
                    "FMUstate is a null pointer".into(),
                ));
            }
            let data = slice(bytes as *const u8, size, "serializedState")?;
            Instance::check_state_bytes(data)?;
            if (*state).is_null() {
                *state = Box::into_raw(Box::new(data.to_vec())) as fmi2FMUstate;
            } else {
                *(*state as *mut Saved) = data.to_vec();
            }
            Ok(Status::Ok)
        })
    }
}

// ---- Functions FtFusion does not provide -----------------------------------------------

/// fmi2GetDirectionalDerivative: not provided (providesDirectionalDerivative = false).
///
/// # Safety
/// `c` as for [`fmi2FreeInstance`].
#[unsafe(no_mangle)]
pub unsafe extern "C" fn fmi2GetDirectionalDerivative(
    c: fmi2Component,
    _unknown: *const fmi2ValueReference,
    _n_unknown: usize,
    _known: *const fmi2ValueReference,
    _n_known: usize,
    _dv_known: *const fmi2Real,
    _dv_unknown: *mut fmi2Real,
) -> fmi2Status {
    // SAFETY: the caller's contract.
    unsafe {
        with(c, Call::GetDirectionalDerivative, |comp| {
            comp.instance.unsupported(Call::GetDirectionalDerivative)
        })
    }
}

/// fmi2SetRealInputDerivatives: not provided (canInterpolateInputs = false).
///
/// # Safety
/// `c` as for [`fmi2FreeInstance`].
#[unsafe(no_mangle)]
pub unsafe extern "C" fn fmi2SetRealInputDerivatives(
    c: fmi2Component,
    _vr: *const fmi2ValueReference,
    _nvr: usize,
    _order: *const fmi2Integer,
    _value: *const fmi2Real,
) -> fmi2Status {
    // SAFETY: the caller's contract.
    unsafe {
        with(c, Call::SetRealInputDerivatives, |comp| {
            comp.instance.unsupported(Call::SetRealInputDerivatives)
        })
    }
}

/// fmi2GetRealOutputDerivatives: not provided (maxOutputDerivativeOrder = 0).
///
/// # Safety
/// `c` as for [`fmi2FreeInstance`].
#[unsafe(no_mangle)]
pub unsafe extern "C" fn fmi2GetRealOutputDerivatives(
    c: fmi2Component,
    _vr: *const fmi2ValueReference,
    _nvr: usize,
    _order: *const fmi2Integer,
    _value: *mut fmi2Real,
) -> fmi2Status {
    // SAFETY: the caller's contract.
    unsafe {
        with(c, Call::GetRealOutputDerivatives, |comp| {
            comp.instance.unsupported(Call::GetRealOutputDerivatives)
        })
    }
}

// ---- Stepping ----------------------------------------------------------------------------

/// fmi2DoStep: takes a contact measurement on a rising `contact` edge.
///
/// # Safety
/// `c` as for [`fmi2FreeInstance`].
#[unsafe(no_mangle)]
pub unsafe extern "C" fn fmi2DoStep(
    c: fmi2Component,
    current_communication_point: fmi2Real,
    communication_step_size: fmi2Real,
    _no_set_fmu_state_prior_to_current_point: fmi2Boolean,
) -> fmi2Status {
    // SAFETY: the caller's contract.
    unsafe {
        with(c, Call::DoStep, |comp| {
            comp.instance
                .do_step(current_communication_point, communication_step_size)
        })
    }
}

/// fmi2CancelStep: steps finish inside fmi2DoStep, so there is never one to cancel.
///
/// # Safety
/// `c` as for [`fmi2FreeInstance`].
#[unsafe(no_mangle)]
pub unsafe extern "C" fn fmi2CancelStep(c: fmi2Component) -> fmi2Status {
    // SAFETY: the caller's contract.
    unsafe { with(c, Call::CancelStep, |_| Ok(Status::Ok)) }
}

/// fmi2GetStatus: steps never return fmi2Pending, so there is no status to ask for.
///
/// # Safety
/// `c` as for [`fmi2FreeInstance`]; `value` writable.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn fmi2GetStatus(
    c: fmi2Component,
    _s: fmi2StatusKind,
    _value: *mut fmi2Status,
) -> fmi2Status {
    // SAFETY: the caller's contract.
    unsafe { with(c, Call::GetStatus("fmi2GetStatus"), |_| Ok(Status::Discard)) }
}

/// fmi2GetRealStatus: fmi2LastSuccessfulTime gives the time reached by the last step.
///
/// # Safety
/// `c` as for [`fmi2FreeInstance`]; `value` writable.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn fmi2GetRealStatus(
    c: fmi2Component,
    s: fmi2StatusKind,
    value: *mut fmi2Real,
) -> fmi2Status {
    // SAFETY: the caller's contract.
    unsafe {
        with(c, Call::GetStatus("fmi2GetRealStatus"), |comp| {
            if s != fmi2StatusKind_fmi2LastSuccessfulTime {
                return Ok(Status::Discard);
            }
            let out = slice_mut(value, 1, "value")?;
            out[0] = comp.instance.last_successful_time()?;
            Ok(Status::Ok)
        })
    }
}

/// fmi2GetIntegerStatus: no integer status exists.
///
/// # Safety
/// `c` as for [`fmi2FreeInstance`].
#[unsafe(no_mangle)]
pub unsafe extern "C" fn fmi2GetIntegerStatus(
    c: fmi2Component,
    _s: fmi2StatusKind,
    _value: *mut fmi2Integer,
) -> fmi2Status {
    // SAFETY: the caller's contract.
    unsafe {
        with(c, Call::GetStatus("fmi2GetIntegerStatus"), |_| {
            Ok(Status::Discard)
        })
    }
}

/// fmi2GetBooleanStatus: fmi2Terminated is always false (the FMU never ends a run).
///
/// # Safety
/// `c` as for [`fmi2FreeInstance`]; `value` writable.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn fmi2GetBooleanStatus(
    c: fmi2Component,
    s: fmi2StatusKind,
    value: *mut fmi2Boolean,
) -> fmi2Status {
    // SAFETY: the caller's contract.
    unsafe {
        with(c, Call::GetStatus("fmi2GetBooleanStatus"), |_| {
            if s != fmi2StatusKind_fmi2Terminated {
                return Ok(Status::Discard);
            }
            slice_mut(value, 1, "value")?[0] = 0;
            Ok(Status::Ok)
        })
    }
}

/// fmi2GetStringStatus: no string status exists (steps are never pending).
///
/// # Safety
/// `c` as for [`fmi2FreeInstance`].
#[unsafe(no_mangle)]
pub unsafe extern "C" fn fmi2GetStringStatus(
    c: fmi2Component,
    _s: fmi2StatusKind,
    _value: *mut fmi2String,
) -> fmi2Status {
    // SAFETY: the caller's contract.
    unsafe {
        with(c, Call::GetStatus("fmi2GetStringStatus"), |_| {
            Ok(Status::Discard)
        })
    }
}

// ---- Every export checked against the official FMI 2.0 function types ------------------

const _: fmi2GetTypesPlatformTYPE = Some(fmi2GetTypesPlatform);
const _: fmi2GetVersionTYPE = Some(fmi2GetVersion);
const _: fmi2SetDebugLoggingTYPE = Some(fmi2SetDebugLogging);
const _: fmi2InstantiateTYPE = Some(fmi2Instantiate);
const _: fmi2FreeInstanceTYPE = Some(fmi2FreeInstance);
const _: fmi2SetupExperimentTYPE = Some(fmi2SetupExperiment);
const _: fmi2EnterInitializationModeTYPE = Some(fmi2EnterInitializationMode);
const _: fmi2ExitInitializationModeTYPE = Some(fmi2ExitInitializationMode);
const _: fmi2TerminateTYPE = Some(fmi2Terminate);
const _: fmi2ResetTYPE = Some(fmi2Reset);
const _: fmi2GetRealTYPE = Some(fmi2GetReal);
const _: fmi2GetIntegerTYPE = Some(fmi2GetInteger);
const _: fmi2GetBooleanTYPE = Some(fmi2GetBoolean);
const _: fmi2GetStringTYPE = Some(fmi2GetString);
const _: fmi2SetRealTYPE = Some(fmi2SetReal);
const _: fmi2SetIntegerTYPE = Some(fmi2SetInteger);
const _: fmi2SetBooleanTYPE = Some(fmi2SetBoolean);
const _: fmi2SetStringTYPE = Some(fmi2SetString);
const _: fmi2GetFMUstateTYPE = Some(fmi2GetFMUstate);
const _: fmi2SetFMUstateTYPE = Some(fmi2SetFMUstate);
const _: fmi2FreeFMUstateTYPE = Some(fmi2FreeFMUstate);
const _: fmi2SerializedFMUstateSizeTYPE = Some(fmi2SerializedFMUstateSize);
const _: fmi2SerializeFMUstateTYPE = Some(fmi2SerializeFMUstate);
const _: fmi2DeSerializeFMUstateTYPE = Some(fmi2DeSerializeFMUstate);
const _: fmi2GetDirectionalDerivativeTYPE = Some(fmi2GetDirectionalDerivative);
const _: fmi2SetRealInputDerivativesTYPE = Some(fmi2SetRealInputDerivatives);
const _: fmi2GetRealOutputDerivativesTYPE = Some(fmi2GetRealOutputDerivatives);
const _: fmi2DoStepTYPE = Some(fmi2DoStep);
const _: fmi2CancelStepTYPE = Some(fmi2CancelStep);
const _: fmi2GetStatusTYPE = Some(fmi2GetStatus);
const _: fmi2GetRealStatusTYPE = Some(fmi2GetRealStatus);
const _: fmi2GetIntegerStatusTYPE = Some(fmi2GetIntegerStatus);
const _: fmi2GetBooleanStatusTYPE = Some(fmi2GetBooleanStatus);
const _: fmi2GetStringStatusTYPE = Some(fmi2GetStringStatus);

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn resource_locations_of_all_spellings_become_folders() {
        for loc in [
            "file:///tmp/fmu/resources",
            "file:////tmp/fmu/resources",
            "file://localhost/tmp/fmu/resources",
        ] {
            assert_eq!(
                resources_dir(Some(loc)),
                Some(PathBuf::from("/tmp/fmu/resources")),
                "{loc}"
            );
        }
        assert_eq!(
            resources_dir(Some("file:///tmp/a%20b/resources")),
            Some(PathBuf::from("/tmp/a b/resources"))
        );
        assert_eq!(resources_dir(None), None);
        assert_eq!(resources_dir(Some("http://example.com/x")), None);
    }

    #[test]
    fn a_panic_is_kept_for_the_logger_with_its_place_not_printed() {
        quiet_panics();
        let caught = std::thread::spawn(|| {
            let p = catch_unwind(|| panic!("capacity overflow")).expect_err("it panicked");
            caught_panic(&*p)
        })
        .join()
        .expect("the thread ends");
        // The default hook again, for the other tests' failures in this process.
        drop(std::panic::take_hook());
        assert!(
            caught.contains("capacity overflow") && caught.contains("fmi2.rs:"),
            "{caught}"
        );
    }
}
