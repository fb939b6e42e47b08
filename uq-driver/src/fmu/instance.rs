//! A Co-Simulation instance of an FMU (`fmi2Component`) with a safe, typed API.

use std::ffi::{c_char, c_int, CString};
use std::fmt;
use std::ptr::{self, NonNull};
use std::sync::atomic::Ordering;
use std::sync::Arc;

use super::binary::{Component, Functions, RawStatus, StatePtr, FMI2_CO_SIMULATION};
use super::description::{ModelDescription, ScalarVariable};
use super::error::{FmuError, LogMessage, Status};
use super::ffi::c_string;
use super::logger::{CallbackFunctions, LogSink};
use super::FmuInner;

/// Where an instance is in the FMI 2.0 Co-Simulation state machine, as far as the importer knows.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum InstanceState {
    /// After `fmi2Instantiate` or `fmi2Reset`.
    Instantiated,
    /// Between `fmi2EnterInitializationMode` and `fmi2ExitInitializationMode`.
    InitializationMode,
    /// Initialized: stepping with `fmi2DoStep`.
    Stepping,
    /// After `fmi2Terminate`.
    Terminated,
    /// A call returned `fmi2Error`: only `reset` (or restoring an FMU state) can continue.
    Error,
    /// A call returned `fmi2Fatal`: no FMI function of this FMU may be called again.
    Fatal,
}

impl fmt::Display for InstanceState {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(match self {
            InstanceState::Instantiated => "instantiated",
            InstanceState::InitializationMode => "in initialization mode",
            InstanceState::Stepping => "initialized",
            InstanceState::Terminated => "terminated",
            InstanceState::Error => "in error (reset it first)",
            InstanceState::Fatal => "fatally failed",
        })
    }
}

/// `fmi2StatusKind`: what `Instance::get_*_status` asks for.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum StatusKind {
    /// `fmi2DoStepStatus`: the status of an asynchronous `fmi2DoStep`.
    DoStepStatus = 0,
    /// `fmi2PendingStatus`: a description of the pending step.
    PendingStatus = 1,
    /// `fmi2LastSuccessfulTime`: the end time of the last successful step (s).
    LastSuccessfulTime = 2,
    /// `fmi2Terminated`: whether the FMU wants to end the simulation.
    Terminated = 3,
}

/// A stored FMU state (`fmi2FMUstate`), valid only with the instance that created it.
///
/// Free it with [`Instance::free_fmu_state`]; a state that is merely dropped stays allocated in
/// the FMU until the instance is freed (if the FMU frees its states then).
#[derive(Debug)]
pub struct FmuState {
    ptr: StatePtr,
    owner: usize,
}

// SAFETY: an FmuState is an opaque handle that is only ever passed back to the FMU through the
// instance that created it (checked with `owner`), and instances are used by one thread at a time.
unsafe impl Send for FmuState {}

/// One instance of an FMU's Co-Simulation slave.
///
/// Create it with [`Fmu::instantiate`](super::Fmu::instantiate). Use one per worker thread: it
/// is `Send` but not `Sync`. Every call that returns a status other than OK or Warning yields
/// [`FmuError::Call`] with the FMU's log messages. Dropping the instance terminates it if it is
/// initialized and frees it (`fmi2FreeInstance`); the FMU's library is unloaded after the last
/// instance and the [`Fmu`](super::Fmu) are gone.
pub struct Instance {
    component: NonNull<std::ffi::c_void>,
    state: InstanceState,
    name: String,
    // The FMU may call back into these until fmi2FreeInstance: both are boxed (stable addresses)
    // and dropped only after `Drop::drop` freed the instance.
    _callbacks: Box<CallbackFunctions>,
    sink: Box<LogSink>,
    // Last, so the library is unloaded after everything else is gone.
    fmu: Arc<FmuInner>,
}

// SAFETY: an FMI 2.0 instance may be driven from any thread as long as calls are not concurrent;
// all calls into the FMU take `&mut self`, and the instance is not `Sync`. The callbacks it hands
// to the FMU (a boxed `LogSink` behind a mutex, calloc/free) are thread-safe.
unsafe impl Send for Instance {}

impl fmt::Debug for Instance {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.debug_struct("Instance")
            .field("name", &self.name)
            .field("state", &self.state)
            .field("fmu", &self.fmu.path)
            .finish_non_exhaustive()
    }
}

/// Checks that two slices passed together have the same length.
fn same_len(function: &'static str, vrs: usize, values: usize) -> Result<(), FmuError> {
    if vrs == values {
        Ok(())
    } else {
        Err(FmuError::InvalidArgument {
            function,
            reason: format!("{vrs} value references but {values} values"),
        })
    }
}

fn c_string_arg(function: &'static str, s: &str) -> Result<CString, FmuError> {
    CString::new(s).map_err(|_| FmuError::InvalidArgument {
        function,
        reason: format!("string contains a NUL byte: {s:?}"),
    })
}

impl Instance {
    pub(crate) fn new(
        fmu: Arc<FmuInner>,
        instance_name: &str,
        logging_on: bool,
    ) -> Result<Instance, FmuError> {
        let failed = |reason: String, messages: Vec<LogMessage>| FmuError::InstantiateFailed {
            path: fmu.path.clone(),
            instance: instance_name.to_string(),
            reason,
            messages,
        };
        if fmu.fatal.load(Ordering::Acquire) {
            return Err(FmuError::Unusable {
                path: fmu.path.clone(),
                function: "fmi2Instantiate",
            });
        }
        let name = c_string_arg("instantiate", instance_name)?;
        let guid = CString::new(fmu.description.guid.as_str())
            .map_err(|_| failed("the GUID contains a NUL byte".into(), Vec::new()))?;
        let resources = CString::new(fmu.resource_uri.as_str())
            .map_err(|_| failed("the resource path contains a NUL byte".into(), Vec::new()))?;

        let alive_before = fmu.live_instances.fetch_add(1, Ordering::AcqRel);
        if fmu
            .description
            .co_simulation
            .can_be_instantiated_only_once_per_process
            && alive_before > 0
        {
            fmu.live_instances.fetch_sub(1, Ordering::AcqRel);
            return Err(failed(
                "the FMU declares canBeInstantiatedOnlyOncePerProcess=\"true\" and another \
                 instance is alive (open the FMU again for another copy of its library)"
                    .into(),
                Vec::new(),
            ));
        }

        let sink = LogSink::new(logging_on);
        let callbacks = CallbackFunctions::new(&sink);
        // SAFETY: all strings are NUL-terminated and outlive the call (the FMU copies them);
        // `callbacks` and the sink it points to are boxed and outlive the instance (see Drop).
        let raw = unsafe {
            (fmu.library.api.instantiate)(
                name.as_ptr(),
                FMI2_CO_SIMULATION,
                guid.as_ptr(),
                resources.as_ptr(),
                &*callbacks,
                0,
                c_int::from(logging_on),
            )
        };
        let Some(component) = NonNull::new(raw) else {
            fmu.live_instances.fetch_sub(1, Ordering::AcqRel);
            return Err(failed("fmi2Instantiate returned null".into(), sink.all()));
        };
        Ok(Instance {
            component,
            state: InstanceState::Instantiated,
            name: instance_name.to_string(),
            _callbacks: callbacks,
            sink,
            fmu,
        })
    }

    /// The instance name passed to `fmi2Instantiate`.
    pub fn name(&self) -> &str {
        &self.name
    }

    /// The state of the instance.
    pub fn state(&self) -> InstanceState {
        self.state
    }

    /// The model description of the FMU.
    pub fn description(&self) -> &ModelDescription {
        &self.fmu.description
    }

    /// The messages the FMU logged (the last 256).
    pub fn messages(&self) -> Vec<LogMessage> {
        self.sink.all()
    }

    /// Forgets the logged messages.
    pub fn clear_messages(&self) {
        self.sink.clear();
    }

    /// Whether to copy the FMU's messages to stderr as they arrive.
    pub fn set_log_echo(&self, echo: bool) {
        self.sink.set_echo(echo);
    }

    // ------------------------------------------------------------------------------------------
    // Call plumbing.

    /// Calls `f` with the function table and the component, then checks the status.
    fn call(
        &mut self,
        function: &'static str,
        f: impl FnOnce(&Functions, Component) -> RawStatus,
    ) -> Result<Status, FmuError> {
        if self.state == InstanceState::Fatal || self.fmu.fatal.load(Ordering::Acquire) {
            return Err(FmuError::Unusable {
                path: self.fmu.path.clone(),
                function,
            });
        }
        let mark = self.sink.mark();
        let raw = f(&self.fmu.library.api, self.component.as_ptr());
        let status = Status::from_raw(raw);
        if status.is_success() {
            return Ok(status);
        }
        match status {
            Status::Fatal => {
                self.state = InstanceState::Fatal;
                self.fmu.fatal.store(true, Ordering::Release);
            }
            Status::Error | Status::Unknown(_) => self.state = InstanceState::Error,
            _ => {}
        }
        Err(FmuError::Call {
            path: self.fmu.path.clone(),
            instance: self.name.clone(),
            function,
            status,
            messages: self.sink.since(mark),
        })
    }

    fn protocol(&self, function: &'static str, reason: &str) -> FmuError {
        FmuError::Protocol {
            path: self.fmu.path.clone(),
            instance: self.name.clone(),
            function,
            reason: reason.to_string(),
        }
    }

    fn unsupported(&self, function: &'static str, declaration: &'static str) -> FmuError {
        FmuError::Unsupported {
            path: self.fmu.path.clone(),
            function,
            declaration,
        }
    }

    // ------------------------------------------------------------------------------------------
    // Life cycle.

    /// `fmi2SetDebugLogging`: turns the FMU's logging on or off, for the given categories (all if
    /// empty).
    pub fn set_debug_logging(&mut self, on: bool, categories: &[&str]) -> Result<(), FmuError> {
        let owned = categories
            .iter()
            .map(|c| c_string_arg("set_debug_logging", c))
            .collect::<Result<Vec<_>, _>>()?;
        let ptrs: Vec<*const c_char> = owned.iter().map(|c| c.as_ptr()).collect();
        self.call("fmi2SetDebugLogging", |api, c| {
            // SAFETY: `ptrs` holds `ptrs.len()` NUL-terminated strings alive during the call.
            unsafe { (api.set_debug_logging)(c, c_int::from(on), ptrs.len(), ptrs.as_ptr()) }
        })?;
        Ok(())
    }

    /// `fmi2SetupExperiment`: relative tolerance, start time and stop time (s).
    pub fn setup_experiment(
        &mut self,
        tolerance: Option<f64>,
        start: f64,
        stop: Option<f64>,
    ) -> Result<(), FmuError> {
        self.call("fmi2SetupExperiment", |api, c| {
            // SAFETY: plain values; `c` is a live component.
            unsafe {
                (api.setup_experiment)(
                    c,
                    c_int::from(tolerance.is_some()),
                    tolerance.unwrap_or(0.0),
                    start,
                    c_int::from(stop.is_some()),
                    stop.unwrap_or(0.0),
                )
            }
        })?;
        Ok(())
    }

    /// `fmi2EnterInitializationMode`.
    pub fn enter_initialization_mode(&mut self) -> Result<(), FmuError> {
        self.call("fmi2EnterInitializationMode", |api, c| {
            // SAFETY: `c` is a live component.
            unsafe { (api.enter_initialization_mode)(c) }
        })?;
        self.state = InstanceState::InitializationMode;
        Ok(())
    }

    /// `fmi2ExitInitializationMode`: afterwards the instance steps.
    pub fn exit_initialization_mode(&mut self) -> Result<(), FmuError> {
        self.call("fmi2ExitInitializationMode", |api, c| {
            // SAFETY: `c` is a live component.
            unsafe { (api.exit_initialization_mode)(c) }
        })?;
        self.state = InstanceState::Stepping;
        Ok(())
    }

    /// `fmi2DoStep`: advances from `current` by `step` (s). `no_set_prior` promises that no
    /// earlier FMU state will be restored.
    pub fn do_step(&mut self, current: f64, step: f64, no_set_prior: bool) -> Result<(), FmuError> {
        self.call("fmi2DoStep", |api, c| {
            // SAFETY: plain values; `c` is a live component.
            unsafe { (api.do_step)(c, current, step, c_int::from(no_set_prior)) }
        })?;
        Ok(())
    }

    /// `fmi2CancelStep` (only meaningful for asynchronous FMUs).
    pub fn cancel_step(&mut self) -> Result<(), FmuError> {
        self.call("fmi2CancelStep", |api, c| {
            // SAFETY: `c` is a live component.
            unsafe { (api.cancel_step)(c) }
        })?;
        Ok(())
    }

    /// `fmi2Terminate`.
    pub fn terminate(&mut self) -> Result<(), FmuError> {
        self.call("fmi2Terminate", |api, c| {
            // SAFETY: `c` is a live component.
            unsafe { (api.terminate)(c) }
        })?;
        self.state = InstanceState::Terminated;
        Ok(())
    }

    /// `fmi2Reset`: back to the state after instantiation, with the start values.
    pub fn reset(&mut self) -> Result<(), FmuError> {
        self.call("fmi2Reset", |api, c| {
            // SAFETY: `c` is a live component.
            unsafe { (api.reset)(c) }
        })?;
        self.state = InstanceState::Instantiated;
        Ok(())
    }

    // ------------------------------------------------------------------------------------------
    // Values.

    /// `fmi2SetReal`.
    pub fn set_real(&mut self, vrs: &[u32], values: &[f64]) -> Result<(), FmuError> {
        same_len("set_real", vrs.len(), values.len())?;
        self.call("fmi2SetReal", |api, c| {
            // SAFETY: both arrays have `vrs.len()` elements.
            unsafe { (api.set_real)(c, vrs.as_ptr(), vrs.len(), values.as_ptr()) }
        })?;
        Ok(())
    }

    /// `fmi2GetReal`.
    pub fn get_real(&mut self, vrs: &[u32], values: &mut [f64]) -> Result<(), FmuError> {
        same_len("get_real", vrs.len(), values.len())?;
        self.call("fmi2GetReal", |api, c| {
            // SAFETY: both arrays have `vrs.len()` elements; the output is writable.
            unsafe { (api.get_real)(c, vrs.as_ptr(), vrs.len(), values.as_mut_ptr()) }
        })?;
        Ok(())
    }

    /// `fmi2SetInteger` (also for Enumeration variables).
    pub fn set_integer(&mut self, vrs: &[u32], values: &[i32]) -> Result<(), FmuError> {
        same_len("set_integer", vrs.len(), values.len())?;
        self.call("fmi2SetInteger", |api, c| {
            // SAFETY: both arrays have `vrs.len()` elements (i32 is a C int).
            unsafe { (api.set_integer)(c, vrs.as_ptr(), vrs.len(), values.as_ptr()) }
        })?;
        Ok(())
    }

    /// `fmi2GetInteger` (also for Enumeration variables).
    pub fn get_integer(&mut self, vrs: &[u32], values: &mut [i32]) -> Result<(), FmuError> {
        same_len("get_integer", vrs.len(), values.len())?;
        self.call("fmi2GetInteger", |api, c| {
            // SAFETY: both arrays have `vrs.len()` elements; the output is writable.
            unsafe { (api.get_integer)(c, vrs.as_ptr(), vrs.len(), values.as_mut_ptr()) }
        })?;
        Ok(())
    }

    /// `fmi2SetBoolean`.
    pub fn set_boolean(&mut self, vrs: &[u32], values: &[bool]) -> Result<(), FmuError> {
        same_len("set_boolean", vrs.len(), values.len())?;
        let raw: Vec<c_int> = values.iter().map(|&b| c_int::from(b)).collect();
        self.call("fmi2SetBoolean", |api, c| {
            // SAFETY: both arrays have `vrs.len()` elements.
            unsafe { (api.set_boolean)(c, vrs.as_ptr(), vrs.len(), raw.as_ptr()) }
        })?;
        Ok(())
    }

    /// `fmi2GetBoolean`.
    pub fn get_boolean(&mut self, vrs: &[u32], values: &mut [bool]) -> Result<(), FmuError> {
        same_len("get_boolean", vrs.len(), values.len())?;
        let mut raw: Vec<c_int> = vec![0; vrs.len()];
        self.call("fmi2GetBoolean", |api, c| {
            // SAFETY: both arrays have `vrs.len()` elements; the output is writable.
            unsafe { (api.get_boolean)(c, vrs.as_ptr(), vrs.len(), raw.as_mut_ptr()) }
        })?;
        for (v, r) in values.iter_mut().zip(raw) {
            *v = r != 0;
        }
        Ok(())
    }

    /// `fmi2SetString`.
    pub fn set_string(&mut self, vrs: &[u32], values: &[&str]) -> Result<(), FmuError> {
        same_len("set_string", vrs.len(), values.len())?;
        let owned = values
            .iter()
            .map(|s| c_string_arg("set_string", s))
            .collect::<Result<Vec<_>, _>>()?;
        let ptrs: Vec<*const c_char> = owned.iter().map(|c| c.as_ptr()).collect();
        self.call("fmi2SetString", |api, c| {
            // SAFETY: both arrays have `vrs.len()` elements; the strings outlive the call.
            unsafe { (api.set_string)(c, vrs.as_ptr(), vrs.len(), ptrs.as_ptr()) }
        })?;
        Ok(())
    }

    /// `fmi2GetString`; the strings are copied at once (the FMU's pointers are short-lived).
    pub fn get_string(&mut self, vrs: &[u32], values: &mut [String]) -> Result<(), FmuError> {
        same_len("get_string", vrs.len(), values.len())?;
        let mut raw: Vec<*const c_char> = vec![ptr::null(); vrs.len()];
        self.call("fmi2GetString", |api, c| {
            // SAFETY: both arrays have `vrs.len()` elements; the output is writable.
            unsafe { (api.get_string)(c, vrs.as_ptr(), vrs.len(), raw.as_mut_ptr()) }
        })?;
        for (v, &p) in values.iter_mut().zip(&raw) {
            // SAFETY: the FMU returned null or NUL-terminated strings valid until its next call.
            match unsafe { c_string(p) } {
                Some(s) => *v = s,
                None => return Err(self.protocol("fmi2GetString", "returned a null string")),
            }
        }
        Ok(())
    }

    /// Looks up a variable of the given base type that may be set in the current state.
    fn settable(&self, name: &str, base_type: &'static str) -> Result<u32, FmuError> {
        let var = self.lookup(name, base_type)?;
        let state = self.state;
        let ok = match state {
            InstanceState::Instantiated => var.settable_before_init(),
            InstanceState::InitializationMode => var.settable_in_initialization_mode(),
            InstanceState::Stepping => var.settable_after_init(),
            _ => false,
        };
        if ok {
            return Ok(var.value_reference);
        }
        let attrs = format!(
            "causality=\"{}\", variability=\"{}\"{}",
            var.causality.as_str(),
            var.variability.as_str(),
            var.effective_initial()
                .map(|i| format!(", initial=\"{}\"", i.as_str()))
                .unwrap_or_default()
        );
        let why = match state {
            InstanceState::Instantiated => format!(
                "before initialization only inputs and non-constant variables with initial \
                 exact or approx can be set; it has {attrs}"
            ),
            InstanceState::InitializationMode => format!(
                "in initialization mode only inputs and non-constant variables with initial \
                 exact can be set; it has {attrs}"
            ),
            InstanceState::Stepping => format!(
                "after initialization only inputs and tunable parameters can be set; it has {attrs}"
            ),
            other => format!("the instance is {other}"),
        };
        Err(FmuError::NotSettable {
            name: name.to_string(),
            why,
        })
    }

    fn lookup(&self, name: &str, base_type: &'static str) -> Result<&ScalarVariable, FmuError> {
        let var = self
            .fmu
            .description
            .variable(name)
            .ok_or_else(|| FmuError::UnknownVariable {
                name: name.to_string(),
            })?;
        if var.kind.base_type() != base_type {
            return Err(FmuError::WrongType {
                name: name.to_string(),
                expected: base_type,
                found: var.kind.type_name(),
            });
        }
        Ok(var)
    }

    /// Sets the Real variable `name`, after checking that FMI 2.0 allows setting it now.
    pub fn set_real_by_name(&mut self, name: &str, value: f64) -> Result<(), FmuError> {
        let vr = self.settable(name, "Real")?;
        self.set_real(&[vr], &[value])
    }

    /// Reads the Real variable `name`.
    pub fn get_real_by_name(&mut self, name: &str) -> Result<f64, FmuError> {
        let vr = self.lookup(name, "Real")?.value_reference;
        let mut value = [0.0];
        self.get_real(&[vr], &mut value)?;
        Ok(value[0])
    }

    // ------------------------------------------------------------------------------------------
    // Derivatives.

    /// `fmi2GetDirectionalDerivative`: `dv_unknown = J · dv_known` for the given value references.
    pub fn get_directional_derivative(
        &mut self,
        unknowns: &[u32],
        knowns: &[u32],
        dv_known: &[f64],
        dv_unknown: &mut [f64],
    ) -> Result<(), FmuError> {
        if !self
            .fmu
            .description
            .co_simulation
            .provides_directional_derivative
        {
            return Err(self.unsupported(
                "fmi2GetDirectionalDerivative",
                "providesDirectionalDerivative=\"false\"",
            ));
        }
        same_len("get_directional_derivative", knowns.len(), dv_known.len())?;
        same_len(
            "get_directional_derivative",
            unknowns.len(),
            dv_unknown.len(),
        )?;
        self.call("fmi2GetDirectionalDerivative", |api, c| {
            // SAFETY: each array has the length passed with it; the output is writable.
            unsafe {
                (api.get_directional_derivative)(
                    c,
                    unknowns.as_ptr(),
                    unknowns.len(),
                    knowns.as_ptr(),
                    knowns.len(),
                    dv_known.as_ptr(),
                    dv_unknown.as_mut_ptr(),
                )
            }
        })?;
        Ok(())
    }

    /// `fmi2SetRealInputDerivatives`: derivatives of the given `order` of Real inputs.
    pub fn set_real_input_derivatives(
        &mut self,
        vrs: &[u32],
        orders: &[i32],
        values: &[f64],
    ) -> Result<(), FmuError> {
        if !self.fmu.description.co_simulation.can_interpolate_inputs {
            return Err(self.unsupported(
                "fmi2SetRealInputDerivatives",
                "canInterpolateInputs=\"false\"",
            ));
        }
        same_len("set_real_input_derivatives", vrs.len(), orders.len())?;
        same_len("set_real_input_derivatives", vrs.len(), values.len())?;
        self.call("fmi2SetRealInputDerivatives", |api, c| {
            // SAFETY: all arrays have `vrs.len()` elements.
            unsafe {
                (api.set_real_input_derivatives)(
                    c,
                    vrs.as_ptr(),
                    vrs.len(),
                    orders.as_ptr(),
                    values.as_ptr(),
                )
            }
        })?;
        Ok(())
    }

    /// `fmi2GetRealOutputDerivatives`: derivatives of the given `order` of Real outputs.
    pub fn get_real_output_derivatives(
        &mut self,
        vrs: &[u32],
        orders: &[i32],
        values: &mut [f64],
    ) -> Result<(), FmuError> {
        if self
            .fmu
            .description
            .co_simulation
            .max_output_derivative_order
            == 0
        {
            return Err(self.unsupported(
                "fmi2GetRealOutputDerivatives",
                "maxOutputDerivativeOrder=\"0\"",
            ));
        }
        same_len("get_real_output_derivatives", vrs.len(), orders.len())?;
        same_len("get_real_output_derivatives", vrs.len(), values.len())?;
        self.call("fmi2GetRealOutputDerivatives", |api, c| {
            // SAFETY: all arrays have `vrs.len()` elements; the output is writable.
            unsafe {
                (api.get_real_output_derivatives)(
                    c,
                    vrs.as_ptr(),
                    vrs.len(),
                    orders.as_ptr(),
                    values.as_mut_ptr(),
                )
            }
        })?;
        Ok(())
    }

    // ------------------------------------------------------------------------------------------
    // Status queries.

    /// `fmi2GetStatus`.
    pub fn get_status(&mut self, kind: StatusKind) -> Result<Status, FmuError> {
        let mut value: RawStatus = 0;
        self.call("fmi2GetStatus", |api, c| {
            // SAFETY: `value` is writable.
            unsafe { (api.get_status)(c, kind as c_int, &mut value) }
        })?;
        Ok(Status::from_raw(value))
    }

    /// `fmi2GetRealStatus` (e.g. [`StatusKind::LastSuccessfulTime`], in s).
    pub fn get_real_status(&mut self, kind: StatusKind) -> Result<f64, FmuError> {
        let mut value = 0.0;
        self.call("fmi2GetRealStatus", |api, c| {
            // SAFETY: `value` is writable.
            unsafe { (api.get_real_status)(c, kind as c_int, &mut value) }
        })?;
        Ok(value)
    }

    /// `fmi2GetIntegerStatus`.
    pub fn get_integer_status(&mut self, kind: StatusKind) -> Result<i32, FmuError> {
        let mut value: c_int = 0;
        self.call("fmi2GetIntegerStatus", |api, c| {
            // SAFETY: `value` is writable.
            unsafe { (api.get_integer_status)(c, kind as c_int, &mut value) }
        })?;
        Ok(value)
    }

    /// `fmi2GetBooleanStatus` (e.g. [`StatusKind::Terminated`]).
    pub fn get_boolean_status(&mut self, kind: StatusKind) -> Result<bool, FmuError> {
        let mut value: c_int = 0;
        self.call("fmi2GetBooleanStatus", |api, c| {
            // SAFETY: `value` is writable.
            unsafe { (api.get_boolean_status)(c, kind as c_int, &mut value) }
        })?;
        Ok(value != 0)
    }

    /// `fmi2GetStringStatus` (e.g. [`StatusKind::PendingStatus`]).
    pub fn get_string_status(&mut self, kind: StatusKind) -> Result<String, FmuError> {
        let mut value: *const c_char = ptr::null();
        self.call("fmi2GetStringStatus", |api, c| {
            // SAFETY: `value` is writable.
            unsafe { (api.get_string_status)(c, kind as c_int, &mut value) }
        })?;
        // SAFETY: the FMU returned null or a NUL-terminated string valid until its next call.
        unsafe { c_string(value) }
            .ok_or_else(|| self.protocol("fmi2GetStringStatus", "returned a null string"))
    }

    // ------------------------------------------------------------------------------------------
    // FMU state.

    fn owner_id(&self) -> usize {
        &*self.sink as *const LogSink as usize
    }

    fn check_state_support(&self, function: &'static str) -> Result<(), FmuError> {
        if self.fmu.description.co_simulation.can_get_and_set_fmu_state {
            Ok(())
        } else {
            Err(self.unsupported(function, "canGetAndSetFMUstate=\"false\""))
        }
    }

    fn check_owner(&self, function: &'static str, state: &FmuState) -> Result<(), FmuError> {
        if state.owner == self.owner_id() {
            Ok(())
        } else {
            Err(FmuError::InvalidArgument {
                function,
                reason: "the FMU state belongs to another instance".into(),
            })
        }
    }

    /// `fmi2GetFMUstate`: stores a copy of the instance's state.
    pub fn get_fmu_state(&mut self) -> Result<FmuState, FmuError> {
        self.check_state_support("fmi2GetFMUstate")?;
        let mut state: StatePtr = ptr::null_mut();
        self.call("fmi2GetFMUstate", |api, c| {
            // SAFETY: `state` is a writable null pointer, so the FMU allocates a new state.
            unsafe { (api.get_fmu_state)(c, &mut state) }
        })?;
        if state.is_null() {
            return Err(self.protocol("fmi2GetFMUstate", "returned a null state"));
        }
        Ok(FmuState {
            ptr: state,
            owner: self.owner_id(),
        })
    }

    /// `fmi2SetFMUstate`: restores a stored state (also possible after an Error).
    pub fn set_fmu_state(&mut self, state: &FmuState) -> Result<(), FmuError> {
        self.check_state_support("fmi2SetFMUstate")?;
        self.check_owner("set_fmu_state", state)?;
        let before = self.state;
        self.call("fmi2SetFMUstate", |api, c| {
            // SAFETY: `state.ptr` came from this instance's fmi2GetFMUstate or
            // fmi2DeSerializeFMUstate and has not been freed (freeing consumes the handle).
            unsafe { (api.set_fmu_state)(c, state.ptr) }
        })?;
        if before == InstanceState::Error {
            self.state = InstanceState::Stepping;
        }
        Ok(())
    }

    /// `fmi2FreeFMUstate`.
    pub fn free_fmu_state(&mut self, state: FmuState) -> Result<(), FmuError> {
        self.check_owner("free_fmu_state", &state)?;
        let mut ptr = state.ptr;
        self.call("fmi2FreeFMUstate", |api, c| {
            // SAFETY: `ptr` is a live state of this instance; the handle is consumed.
            unsafe { (api.free_fmu_state)(c, &mut ptr) }
        })?;
        Ok(())
    }

    /// `fmi2SerializedFMUstateSize` and `fmi2SerializeFMUstate`: the state as bytes.
    pub fn serialize_fmu_state(&mut self, state: &FmuState) -> Result<Vec<u8>, FmuError> {
        if !self.fmu.description.co_simulation.can_serialize_fmu_state {
            return Err(self.unsupported("fmi2SerializeFMUstate", "canSerializeFMUstate=\"false\""));
        }
        self.check_owner("serialize_fmu_state", state)?;
        let mut size = 0usize;
        self.call("fmi2SerializedFMUstateSize", |api, c| {
            // SAFETY: `state.ptr` is a live state of this instance; `size` is writable.
            unsafe { (api.serialized_fmu_state_size)(c, state.ptr, &mut size) }
        })?;
        let mut bytes = vec![0u8; size];
        self.call("fmi2SerializeFMUstate", |api, c| {
            // SAFETY: `bytes` has the `size` bytes the FMU asked for.
            unsafe { (api.serialize_fmu_state)(c, state.ptr, bytes.as_mut_ptr().cast(), size) }
        })?;
        Ok(bytes)
    }

    /// `fmi2DeSerializeFMUstate`: a state from bytes made by [`Instance::serialize_fmu_state`].
    pub fn deserialize_fmu_state(&mut self, bytes: &[u8]) -> Result<FmuState, FmuError> {
        if !self.fmu.description.co_simulation.can_serialize_fmu_state {
            return Err(
                self.unsupported("fmi2DeSerializeFMUstate", "canSerializeFMUstate=\"false\"")
            );
        }
        let mut state: StatePtr = ptr::null_mut();
        self.call("fmi2DeSerializeFMUstate", |api, c| {
            // SAFETY: `bytes` has `bytes.len()` readable bytes; `state` is a writable null
            // pointer, so the FMU allocates a new state.
            unsafe {
                (api.deserialize_fmu_state)(c, bytes.as_ptr().cast(), bytes.len(), &mut state)
            }
        })?;
        if state.is_null() {
            return Err(self.protocol("fmi2DeSerializeFMUstate", "returned a null state"));
        }
        Ok(FmuState {
            ptr: state,
            owner: self.owner_id(),
        })
    }
}

impl Drop for Instance {
    fn drop(&mut self) {
        let fatal = self.state == InstanceState::Fatal || self.fmu.fatal.load(Ordering::Acquire);
        // After fmi2Fatal, FMI 2.0 forbids every further call, fmi2FreeInstance included.
        if !fatal {
            let api = &self.fmu.library.api;
            let c = self.component.as_ptr();
            if self.state == InstanceState::Stepping {
                // SAFETY: `c` is a live, initialized component; the status is irrelevant here.
                let _ = unsafe { (api.terminate)(c) };
            }
            // SAFETY: `c` is live and is never used again; the callbacks it may use until it
            // returns are still alive (dropped after this function).
            unsafe { (api.free_instance)(c) };
        }
        self.fmu.live_instances.fetch_sub(1, Ordering::AcqRel);
        // The callbacks, the sink and the library are dropped with the fields, after this.
    }
}
