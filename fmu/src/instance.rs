//! One FMU instance, without FFI: the FMI 2.0 Co-Simulation state machine (one allowed-
//! state mask per function, after Reference-FMUs), the variable store read and written
//! through the variable table, the filter driven by `doStep`, saved states as versioned
//! bytes, and status escalation and logging in one place ([`Instance::finish`]).

use std::path::{Path, PathBuf};

use model_description::{self as md, Causality, VARIABLES, VarType};

use crate::error::{FusionError, Result};
use crate::filter::{Filter, Measurement, Reader, VisionMeasurement, VisionSense, Writer};
use crate::params::{Params, Store, Value, index_of, index_of_vr};
use crate::trace::Trace;

/// First bytes of a saved FMU state.
pub const STATE_MAGIC: [u8; 8] = *b"FTFSTATE";
/// Version of the saved-state layout (2: the `vision.valid` edge; 3: the filter's evidence
/// that its particles are lost; 4: the `centre_map` parameter; 5: `mismatch_position`; 6:
/// `mismatch_interpolation`; 7: `mismatch_reach` and the filter's contact poses; 8:
/// `mismatch_lever`).
pub const STATE_VERSION: u32 = 8;

/// FMI 2.0 status of a call.
#[derive(Debug, Clone, Copy, PartialEq, Eq, PartialOrd, Ord)]
pub enum Status {
    /// fmi2OK.
    Ok,
    /// fmi2Warning.
    Warning,
    /// fmi2Discard.
    Discard,
    /// fmi2Error.
    Error,
    /// fmi2Fatal.
    Fatal,
}

/// The states of the FMI 2.0 Co-Simulation state machine an instance can be in.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Mode {
    /// After fmi2Instantiate or fmi2Reset.
    Instantiated = 1,
    /// Between fmi2EnterInitializationMode and fmi2ExitInitializationMode.
    InitializationMode = 2,
    /// Initialized, ready for fmi2DoStep.
    StepComplete = 4,
    /// After fmi2Terminate.
    Terminated = 8,
    /// After a failed initialization: only getters, state functions, reset and free.
    Error = 16,
}

impl Mode {
    /// The state's name for messages.
    pub fn name(self) -> &'static str {
        match self {
            Mode::Instantiated => "Instantiated",
            Mode::InitializationMode => "InitializationMode",
            Mode::StepComplete => "StepComplete",
            Mode::Terminated => "Terminated",
            Mode::Error => "Error",
        }
    }
}

const INST: u8 = Mode::Instantiated as u8;
const INIT: u8 = Mode::InitializationMode as u8;
const STEP: u8 = Mode::StepComplete as u8;
const TERM: u8 = Mode::Terminated as u8;
const ERR: u8 = Mode::Error as u8;
const ANY: u8 = INST | INIT | STEP | TERM | ERR;

/// The FMI functions that act on an instance, with the states each is allowed in.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Call {
    /// fmi2SetDebugLogging.
    SetDebugLogging,
    /// fmi2SetupExperiment.
    SetupExperiment,
    /// fmi2EnterInitializationMode.
    EnterInitializationMode,
    /// fmi2ExitInitializationMode.
    ExitInitializationMode,
    /// fmi2Terminate.
    Terminate,
    /// fmi2Reset.
    Reset,
    /// fmi2GetReal / Integer / Boolean / String.
    Get(&'static str),
    /// fmi2SetReal / Integer / Boolean / String.
    Set(&'static str),
    /// fmi2GetFMUstate, fmi2SetFMUstate, fmi2FreeFMUstate and the serialization functions.
    State(&'static str),
    /// fmi2GetDirectionalDerivative.
    GetDirectionalDerivative,
    /// fmi2SetRealInputDerivatives.
    SetRealInputDerivatives,
    /// fmi2GetRealOutputDerivatives.
    GetRealOutputDerivatives,
    /// fmi2DoStep.
    DoStep,
    /// fmi2CancelStep.
    CancelStep,
    /// fmi2GetStatus and its typed variants.
    GetStatus(&'static str),
}

impl Call {
    /// The C function's name.
    pub fn name(self) -> &'static str {
        match self {
            Call::SetDebugLogging => "fmi2SetDebugLogging",
            Call::SetupExperiment => "fmi2SetupExperiment",
            Call::EnterInitializationMode => "fmi2EnterInitializationMode",
            Call::ExitInitializationMode => "fmi2ExitInitializationMode",
            Call::Terminate => "fmi2Terminate",
            Call::Reset => "fmi2Reset",
            Call::Get(n) | Call::Set(n) | Call::State(n) | Call::GetStatus(n) => n,
            Call::GetDirectionalDerivative => "fmi2GetDirectionalDerivative",
            Call::SetRealInputDerivatives => "fmi2SetRealInputDerivatives",
            Call::GetRealOutputDerivatives => "fmi2GetRealOutputDerivatives",
            Call::DoStep => "fmi2DoStep",
            Call::CancelStep => "fmi2CancelStep",
        }
    }

    /// The states the function is allowed in (FMI 2.0, section 4.2.4).
    pub fn mask(self) -> u8 {
        match self {
            Call::SetDebugLogging | Call::Reset | Call::State(_) => ANY,
            Call::SetupExperiment | Call::EnterInitializationMode => INST,
            Call::ExitInitializationMode => INIT,
            Call::Terminate | Call::DoStep => STEP,
            Call::Get(_) | Call::GetDirectionalDerivative => INIT | STEP | TERM | ERR,
            Call::Set(_) | Call::SetRealInputDerivatives => INST | INIT | STEP,
            Call::GetRealOutputDerivatives => STEP | TERM | ERR,
            Call::GetStatus(_) => STEP | TERM,
            // Steps finish before fmi2DoStep returns: there is never one to cancel.
            Call::CancelStep => 0,
        }
    }
}

/// Receives the instance's messages: status, category, text.
pub type Logger = Box<dyn Fn(Status, &str, &str)>;

/// Table positions of the variables `doStep` reads and writes.
#[derive(Debug, Clone)]
struct Io {
    wrench: [usize; 6],
    tcp: [usize; 6],
    contact: usize,
    slide: usize,
    slide_start: [usize; 3],
    slide_end_valid: usize,
    slide_end: [usize; 3],
    /// vision.left_distance, right_distance, passive_left, passive_right.
    vision: [usize; 4],
    vision_valid: usize,
    /// Estimate and spread outputs by full DOF index (grip x..rz, object x..rz).
    pose: [usize; 12],
    std: [usize; 12],
    confidence: usize,
    converged: usize,
    ess: usize,
    measurements: usize,
    clusters: usize,
    xy_corr: usize,
}

impl Io {
    fn new() -> Self {
        // Full DOF index order: grip x .. rz, then object x .. rz (ftmap's `Dof::index`).
        let full = |grip: [&str; 6], object: [&str; 6]| {
            std::array::from_fn(|i| index_of(if i < 6 { grip[i] } else { object[i - 6] }))
        };
        Self {
            wrench: md::WRENCH.map(index_of),
            tcp: md::TCP.map(index_of),
            contact: index_of(md::CONTACT),
            slide: index_of(md::SLIDE),
            slide_start: md::SLIDE_START.map(index_of),
            slide_end_valid: index_of(md::SLIDE_END_VALID),
            slide_end: md::SLIDE_END.map(index_of),
            vision: md::VISION_FEATURES.map(index_of),
            vision_valid: index_of(md::VISION_VALID),
            pose: full(md::GRIP, md::OBJECT),
            std: full(md::GRIP_STD, md::OBJECT_STD),
            confidence: index_of("confidence"),
            converged: index_of("converged"),
            ess: index_of("ess"),
            measurements: index_of("measurements"),
            clusters: index_of("clusters"),
            xy_corr: index_of(md::OBJECT_XY_CORR),
        }
    }
}

/// An FMU instance.
pub struct Instance {
    name: String,
    resources: Option<PathBuf>,
    logger: Logger,
    logging_on: bool,
    categories: Vec<String>,
    mode: Mode,
    store: Store,
    filter: Option<Filter>,
    /// Where each measurement's particles go (`trace`), when it names a file.
    trace: Option<Trace>,
    prev_contact: bool,
    prev_valid: bool,
    time: f64,
    io: Io,
}

impl std::fmt::Debug for Instance {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("Instance")
            .field("name", &self.name)
            .field("mode", &self.mode)
            .finish_non_exhaustive()
    }
}

impl Instance {
    /// A new instance named `name`, reading relative map names from `resources`.
    pub fn new(name: &str, resources: Option<PathBuf>, logger: Logger, logging_on: bool) -> Self {
        Self {
            name: name.to_owned(),
            resources,
            logger,
            logging_on,
            categories: Vec::new(),
            mode: Mode::Instantiated,
            store: Store::default(),
            filter: None,
            trace: None,
            prev_contact: false,
            prev_valid: false,
            time: 0.0,
            io: Io::new(),
        }
    }

    /// The instance name given at instantiation.
    pub fn name(&self) -> &str {
        &self.name
    }

    /// The current state.
    pub fn mode(&self) -> Mode {
        self.mode
    }

    /// The filter, once initialized.
    pub fn filter(&self) -> Option<&Filter> {
        self.filter.as_ref()
    }

    /// Sends a message to the logger: warnings and errors always, others when logging is on
    /// and the category is enabled (all are, when none was named).
    pub fn log(&self, status: Status, category: &str, msg: &str) {
        let enabled = self.logging_on
            && (self.categories.is_empty() || self.categories.iter().any(|c| c == category));
        if status >= Status::Warning || enabled {
            (self.logger)(status, category, msg);
        }
    }

    /// Errors unless `call` is allowed in the current state.
    pub fn check(&self, call: Call) -> Result<()> {
        if call.mask() & self.mode as u8 != 0 {
            Ok(())
        } else {
            Err(FusionError::IllegalCall {
                call: call.name(),
                mode: self.mode.name(),
            })
        }
    }

    /// Turns the result of `call` into its status: logs errors, and moves the instance to
    /// the Error state when initialization failed (refused calls leave it as it was).
    pub fn finish(&mut self, call: Call, r: Result<Status>) -> Status {
        match r {
            Ok(s) => s,
            Err(e) => {
                if matches!(
                    e,
                    FusionError::Parameter { .. }
                        | FusionError::Map { .. }
                        | FusionError::MapFile(_)
                        | FusionError::Vision { .. }
                        | FusionError::VisionFile(_)
                ) {
                    self.mode = Mode::Error;
                }
                self.log(
                    Status::Error,
                    "logStatusError",
                    &format!("{}: {}", call.name(), crate::error::report(&e)),
                );
                Status::Error
            }
        }
    }

    /// fmi2SetDebugLogging: logging on or off, for the named categories (all when none).
    pub fn set_debug_logging(&mut self, on: bool, categories: &[String]) -> Result<Status> {
        self.check(Call::SetDebugLogging)?;
        let known: Vec<&str> = model_description::LOG_CATEGORIES
            .iter()
            .map(|c| c.0)
            .collect();
        if let Some(bad) = categories.iter().find(|c| !known.contains(&c.as_str())) {
            return Err(FusionError::BadArgument(format!(
                "unknown log category `{bad}` (known: {})",
                known.join(", ")
            )));
        }
        self.logging_on = on;
        self.categories = categories.to_vec();
        Ok(Status::Ok)
    }

    /// fmi2SetupExperiment: the start time.
    pub fn setup_experiment(&mut self, start: f64) -> Result<Status> {
        self.check(Call::SetupExperiment)?;
        if !start.is_finite() {
            return Err(FusionError::BadArgument(format!(
                "start time {start} is not finite"
            )));
        }
        self.time = start;
        Ok(Status::Ok)
    }

    /// fmi2EnterInitializationMode.
    pub fn enter_initialization_mode(&mut self) -> Result<Status> {
        self.check(Call::EnterInitializationMode)?;
        self.mode = Mode::InitializationMode;
        Ok(Status::Ok)
    }

    /// The file a file parameter (`map`, `vision`) names: absolute, or in the resources
    /// folder; the error names the file and why.
    fn resource_path(&self, name: &str) -> std::result::Result<PathBuf, (PathBuf, String)> {
        let given = Path::new(name);
        if given.is_absolute() {
            return Ok(given.to_owned());
        }
        match &self.resources {
            Some(dir) => Ok(dir.join(given)),
            None => Err((
                given.to_owned(),
                "a relative file name needs the FMU's resources location, which the importer did not give".into(),
            )),
        }
    }

    /// fmi2ExitInitializationMode: checks the parameters, loads the map, spreads the particles.
    pub fn exit_initialization_mode(&mut self) -> Result<Status> {
        self.check(Call::ExitInitializationMode)?;
        let (filter, trace) = self.new_filter(&self.store)?;
        self.filter = Some(filter);
        self.trace = trace;
        self.write_outputs();
        self.mode = Mode::StepComplete;
        Ok(Status::Ok)
    }

    /// The filter the parameters in `store` make: checked, its map (and vision model) loaded,
    /// the particles spread; and its trace file, opened, when `trace` names one.
    fn new_filter(&self, store: &Store) -> Result<(Filter, Option<Trace>)> {
        let params = Params::from_store(store)?;
        let trace = params.trace.as_deref().map(Trace::open).transpose()?;
        let path = self
            .resource_path(&params.map)
            .map_err(|(path, reason)| FusionError::Map { path, reason })?;
        let centre = params
            .centre_map
            .as_deref()
            .map(|name| self.resource_path(name))
            .transpose()
            .map_err(|(path, reason)| FusionError::Map { path, reason })?;
        let lookup = crate::shared::map(&path, centre.as_deref())?;
        let task = lookup.task().to_owned();
        let mut filter = Filter::with_lookup(lookup, params.config);
        if let Some(name) = &params.vision {
            let vision_err = |(path, reason)| FusionError::Vision { path, reason };
            let file = self.resource_path(name).map_err(vision_err)?;
            let model = ftmap::vision::VisionModel::load(&file).map_err(FusionError::VisionFile)?;
            match &model.task {
                Some(parts) if *parts != task => {
                    return Err(FusionError::Vision {
                        path: file,
                        reason: format!(
                            "its parts are task `{parts}`'s, the map {} is task `{task}`'s",
                            path.display(),
                        ),
                    });
                }
                Some(_) => {}
                None => self.log(
                    Status::Ok,
                    "logFilter",
                    &format!(
                        "vision model {} does not name its task: it is taken to fit the map's, `{task}`",
                        file.display(),
                    ),
                ),
            }
            let sense = VisionSense::new(
                model,
                params.vision_method,
                params.sigma_vision,
                filter.lookup(),
            );
            filter = filter.with_vision(sense);
            self.log(
                Status::Ok,
                "logFilter",
                &format!(
                    "vision model {} ({:?})",
                    file.display(),
                    params.vision_method
                ),
            );
        }
        let dofs = filter.lookup().dof_names();
        self.log(
            Status::Ok,
            "logFilter",
            &format!(
                "map {}{} ({} cells over {}), {} particles",
                path.display(),
                centre
                    .as_ref()
                    .map(|c| format!(" with centre map {}", c.display()))
                    .unwrap_or_default(),
                filter.lookup().cells(),
                dofs.join(", "),
                filter.config().particles
            ),
        );
        Ok((filter, trace))
    }

    /// fmi2Terminate.
    pub fn terminate(&mut self) -> Result<Status> {
        self.check(Call::Terminate)?;
        self.mode = Mode::Terminated;
        Ok(Status::Ok)
    }

    /// fmi2Reset: back to the state after instantiation, start values restored.
    pub fn reset(&mut self) -> Result<Status> {
        self.check(Call::Reset)?;
        self.mode = Mode::Instantiated;
        self.store = Store::default();
        self.filter = None;
        self.trace = None;
        self.prev_contact = false;
        self.prev_valid = false;
        self.time = 0.0;
        Ok(Status::Ok)
    }

    /// Table position of `vr` if it is a variable of type `ty`.
    fn lookup_vr(&self, vr: u32, ty: VarType) -> Result<usize> {
        let i = index_of_vr(vr).ok_or_else(|| {
            FusionError::BadArgument(format!("no variable has value reference {vr}"))
        })?;
        if VARIABLES[i].ty != ty {
            return Err(FusionError::BadArgument(format!(
                "value reference {vr} is `{}` of type {:?}, not {ty:?}",
                VARIABLES[i].name, VARIABLES[i].ty
            )));
        }
        Ok(i)
    }

    /// Reads variables of type `ty`: `read(table position)` for each value reference.
    pub fn get<T>(
        &self,
        ty: VarType,
        vrs: &[u32],
        out: &mut [T],
        read: impl Fn(&Value) -> T,
    ) -> Result<Status> {
        self.check(Call::Get(get_name(ty)))?;
        if vrs.len() != out.len() {
            return Err(FusionError::BadArgument(format!(
                "{} value references, {} values",
                vrs.len(),
                out.len()
            )));
        }
        let idx = vrs
            .iter()
            .map(|&vr| self.lookup_vr(vr, ty))
            .collect::<Result<Vec<_>>>()?;
        for (o, i) in out.iter_mut().zip(idx) {
            *o = read(self.store.get(i));
        }
        Ok(Status::Ok)
    }

    /// Writes variables of type `ty`; refuses outputs, and parameters after initialization.
    /// All value references are checked before any value is written.
    pub fn set(&mut self, ty: VarType, vrs: &[u32], values: Vec<Value>) -> Result<Status> {
        self.check(Call::Set(set_name(ty)))?;
        if vrs.len() != values.len() {
            return Err(FusionError::BadArgument(format!(
                "{} value references, {} values",
                vrs.len(),
                values.len()
            )));
        }
        let mut idx = Vec::with_capacity(vrs.len());
        for &vr in vrs {
            let i = self.lookup_vr(vr, ty)?;
            let v = &VARIABLES[i];
            match v.causality {
                Causality::Output => {
                    return Err(FusionError::BadArgument(format!(
                        "`{}` is an output and cannot be set",
                        v.name
                    )));
                }
                Causality::Parameter
                    if !matches!(self.mode, Mode::Instantiated | Mode::InitializationMode) =>
                {
                    return Err(FusionError::BadArgument(format!(
                        "parameter `{}` is fixed: it can only be set before fmi2ExitInitializationMode",
                        v.name
                    )));
                }
                _ => idx.push(i),
            }
        }
        let mut status = Status::Ok;
        for (i, value) in idx.into_iter().zip(values) {
            if let Value::Real(x) = value
                && !x.is_finite()
                && VARIABLES[i].causality == Causality::Input
            {
                self.log(
                    Status::Warning,
                    "logStatusWarning",
                    &format!(
                        "input `{}` set to {x}: a measurement taken with it will be skipped",
                        VARIABLES[i].name
                    ),
                );
                status = Status::Warning;
            }
            *self.store.get_mut(i) = value;
        }
        Ok(status)
    }

    /// fmi2DoStep: takes a measurement when `contact` rose since the last step (with the
    /// image's detections when `vision.valid` is set), or an image alone when `vision.valid`
    /// rose while `contact` is false.
    pub fn do_step(&mut self, t: f64, h: f64) -> Result<Status> {
        self.check(Call::DoStep)?;
        if !(h >= 0.0 && h.is_finite() && t.is_finite()) {
            return Err(FusionError::BadArgument(format!(
                "communication point {t}, step size {h}: need finite, h >= 0"
            )));
        }
        let contact = self.store.boolean(self.io.contact);
        let valid = self.store.boolean(self.io.vision_valid);
        let rising = contact && !self.prev_contact;
        let image_alone = valid && !self.prev_valid && !contact;
        self.prev_contact = contact;
        self.prev_valid = valid;
        self.time = t + h;
        if !(rising || image_alone) {
            return Ok(Status::Ok);
        }
        let v = self.io.vision.map(|i| self.store.real(i));
        let slide = self.store.boolean(self.io.slide);
        let m = Measurement {
            wrench: self.io.wrench.map(|i| self.store.real(i)),
            tcp: self.io.tcp.map(|i| self.store.real(i)),
            vision: valid.then_some(VisionMeasurement {
                distances: [v[0], v[1]],
                passive: [v[2], v[3]],
            }),
            vision_only: image_alone,
            slide_start: slide.then(|| self.io.slide_start.map(|i| self.store.real(i))),
            slide_end: (slide && self.store.boolean(self.io.slide_end_valid))
                .then(|| self.io.slide_end.map(|i| self.store.real(i))),
        };
        let Some(filter) = self.filter.as_mut() else {
            return Err(FusionError::IllegalCall {
                call: "fmi2DoStep",
                mode: "uninitialized",
            });
        };
        match filter.measure(&m) {
            Ok(report) => {
                self.write_outputs();
                let e = self
                    .filter
                    .as_ref()
                    .map(|f| f.estimate().clone())
                    .unwrap_or_default();
                self.log(
                    Status::Ok,
                    "logFilter",
                    &format!(
                        "t = {}: measurement {}: estimate {:?}, confidence {:.3}, ESS {:.0}, clusters {}",
                        self.time,
                        self.store.integer(self.io.measurements),
                        e.pose,
                        e.confidence,
                        e.ess,
                        e.clusters
                    ),
                );
                let mut status = Status::Ok;
                if report.vision_unused {
                    let why = if self.filter.as_ref().is_some_and(|f| f.vision().is_some()) {
                        "no camera displacement fits the passive part's detected edges (vision_method 1)"
                    } else {
                        "no vision model is loaded (parameter `vision` is empty)"
                    };
                    self.log(
                        Status::Warning,
                        "logStatusWarning",
                        &format!(
                            "t = {}: vision.valid is set but the image was not used: {why}",
                            self.time
                        ),
                    );
                    status = Status::Warning;
                }
                if let (Some(trace), Some(filter)) = (self.trace.as_mut(), self.filter.as_ref())
                    && let Err(e) = trace.append(filter.measurements(), filter)
                {
                    let path = trace.path().display().to_string();
                    self.log(
                        Status::Warning,
                        "logStatusWarning",
                        &format!(
                            "t = {}: the particles could not be appended to trace file {path}: {e}",
                            self.time
                        ),
                    );
                    status = Status::Warning;
                }
                // Not a warning: the filter handled the measurement as designed, and
                // importers (the FMI reference importer among them) end a run at one.
                if report.respread > 0 {
                    self.log(
                        Status::Ok,
                        "logFilter",
                        &format!(
                            "t = {}: no particle explains the measurement (every likelihood underflowed): \
                             re-spread half of the particles uniformly ({} of the iterations)",
                            self.time, report.respread
                        ),
                    );
                }
                if report.relocated > 0 {
                    self.log(
                        Status::Ok,
                        "logFilter",
                        &format!(
                            "t = {}: the particles explain the measurement far worse than a \
                             draw over Omega does (more likely lost than not, parameter lost): \
                             redrew {} of them uniformly",
                            self.time, report.relocated
                        ),
                    );
                }
                Ok(status)
            }
            Err(e @ (FusionError::NonFinite { .. } | FusionError::Absurd { .. })) => {
                self.log(
                    Status::Warning,
                    "logStatusWarning",
                    &format!("t = {}: {e}; estimate unchanged", self.time),
                );
                Ok(Status::Warning)
            }
            Err(e) => Err(e),
        }
    }

    /// Copies the filter's estimate into the output variables.
    fn write_outputs(&mut self) {
        let Some(f) = &self.filter else { return };
        let e = f.estimate();
        for (k, a) in f.lookup().axes().iter().enumerate() {
            self.store.set_real(self.io.pose[a.dof.index()], e.pose[k]);
            self.store.set_real(self.io.std[a.dof.index()], e.std[k]);
        }
        self.store.set_real(self.io.confidence, e.confidence);
        *self.store.get_mut(self.io.converged) = Value::Boolean(e.converged);
        self.store.set_real(self.io.ess, e.ess);
        *self.store.get_mut(self.io.measurements) = Value::Integer(f.measurements() as i32);
        *self.store.get_mut(self.io.clusters) = Value::Integer(e.clusters as i32);
        self.store.set_real(self.io.xy_corr, e.xy_corr);
    }

    /// The instance's state as bytes: magic, version, GUID, variable values, contact edge,
    /// time and the filter (particles, weights, random generator).
    pub fn save_state(&self) -> Result<Vec<u8>> {
        self.check(Call::State("fmi2GetFMUstate"))?;
        let mut w = Writer::default();
        w.0.extend_from_slice(&STATE_MAGIC);
        w.u32(STATE_VERSION);
        w.bytes(model_description::guid().as_bytes());
        self.store.save(&mut w);
        w.u32(u32::from(self.prev_contact));
        w.u32(u32::from(self.prev_valid));
        w.f64(self.time);
        w.u32(u32::from(self.filter.is_some()));
        if let Some(f) = &self.filter {
            f.save(&mut w);
        }
        Ok(w.0)
    }

    /// Restores bytes from [`Instance::save_state`]; refuses foreign or mismatching bytes
    /// and then leaves the instance unchanged.
    pub fn restore_state(&mut self, bytes: &[u8]) -> Result<Status> {
        self.check(Call::State("fmi2SetFMUstate"))?;
        let mut r = Self::state_header(bytes)?;
        let store = Store::restore(&mut r)?;
        let prev_contact = r.u32()? != 0;
        let prev_valid = r.u32()? != 0;
        let time = r.f64()?;
        let has_filter = r.u32()? != 0;
        match (&mut self.filter, has_filter) {
            (Some(f), true) => {
                let mut params = VARIABLES
                    .iter()
                    .enumerate()
                    .filter(|(_, v)| v.causality == Causality::Parameter);
                if let Some((_, v)) = params.find(|(i, _)| store.get(*i) != self.store.get(*i)) {
                    return Err(FusionError::State(format!(
                        "saved with another value of parameter `{}`",
                        v.name
                    )));
                }
                let mut trial = f.clone();
                trial.restore(&mut r)?;
                if !r.done() {
                    return Err(FusionError::State(
                        "bytes after the end of the state".into(),
                    ));
                }
                *f = trial;
            }
            (None, false) if r.done() => {}
            (None, false) => {
                return Err(FusionError::State(
                    "bytes after the end of the state".into(),
                ));
            }
            // A state saved before initialization takes the instance back there.
            (Some(_), false) if r.done() => {
                self.filter = None;
                self.trace = None;
                self.mode = Mode::Instantiated;
            }
            (Some(_), false) => {
                return Err(FusionError::State(
                    "bytes after the end of the state".into(),
                ));
            }
            // A state saved after initialization into an instance not initialized (FMI 2.0
            // allows it; the reference importer restores a saved run this way): initialize
            // with the saved parameters, then restore the filter.
            (None, true) => {
                let (mut filter, trace) = self.new_filter(&store).map_err(|e| {
                    FusionError::State(format!(
                        "its parameters do not initialize this instance: {}",
                        crate::error::report(&e)
                    ))
                })?;
                filter.restore(&mut r)?;
                if !r.done() {
                    return Err(FusionError::State(
                        "bytes after the end of the state".into(),
                    ));
                }
                self.filter = Some(filter);
                self.trace = trace;
                self.mode = Mode::StepComplete;
            }
        }
        // The outputs follow from the restored filter, not from the bytes: a tampered state
        // cannot put a value there that the filter would not give.
        let start = Store::default();
        self.store = store;
        for (i, v) in VARIABLES.iter().enumerate() {
            if v.causality == Causality::Output {
                *self.store.get_mut(i) = start.get(i).clone();
            }
        }
        self.write_outputs();
        self.prev_contact = prev_contact;
        self.prev_valid = prev_valid;
        self.time = time;
        Ok(Status::Ok)
    }

    /// Errors unless `bytes` start like a state of this FMU (magic, version, GUID).
    pub fn check_state_bytes(bytes: &[u8]) -> Result<()> {
        Self::state_header(bytes).map(|_| ())
    }

    /// Reads the header of state bytes; the reader stands after it.
    fn state_header(bytes: &[u8]) -> Result<Reader<'_>> {
        let mut r = Reader::new(bytes);
        if r.take(STATE_MAGIC.len()).ok() != Some(&STATE_MAGIC[..]) {
            return Err(FusionError::State(
                "not an FtFusion state (magic bytes differ)".into(),
            ));
        }
        let version = r.u32()?;
        if version != STATE_VERSION {
            return Err(FusionError::State(format!(
                "state version {version}, this build reads {STATE_VERSION}"
            )));
        }
        if r.bytes()? != model_description::guid().as_bytes() {
            return Err(FusionError::State(
                "saved by an FMU with another interface (GUID differs)".into(),
            ));
        }
        Ok(r)
    }

    /// Puts the instance into the Error state after an internal failure (a caught panic).
    pub fn poison(&mut self) {
        self.mode = Mode::Error;
    }

    /// The answer to a function FtFusion does not provide.
    pub fn unsupported(&self, call: Call) -> Result<Status> {
        self.check(call)?;
        Err(FusionError::Unsupported(call.name()))
    }

    /// fmi2GetRealStatus(fmi2LastSuccessfulTime): the time reached by the last step.
    pub fn last_successful_time(&self) -> Result<f64> {
        self.check(Call::GetStatus("fmi2GetRealStatus"))?;
        Ok(self.time)
    }
}

fn get_name(ty: VarType) -> &'static str {
    match ty {
        VarType::Real => "fmi2GetReal",
        VarType::Integer => "fmi2GetInteger",
        VarType::Boolean => "fmi2GetBoolean",
        VarType::String => "fmi2GetString",
    }
}

fn set_name(ty: VarType) -> &'static str {
    match ty {
        VarType::Real => "fmi2SetReal",
        VarType::Integer => "fmi2SetInteger",
        VarType::Boolean => "fmi2SetBoolean",
        VarType::String => "fmi2SetString",
    }
}

#[cfg(test)]
mod tests;
