//! A Co-Simulation instance of an FMU (`fmi2Component`) with a safe, typed API.

use std::ffi::{c_char, c_int, CString};
use std::fmt;
use std::ptr::NonNull;
use std::sync::atomic::Ordering;
use std::sync::Arc;

use super::binary::{Component, Functions, RawStatus, StatePtr, FMI2_CO_SIMULATION};
use super::description::ModelDescription;
use super::error::{FmuError, LogMessage, Status};
use super::logger::{CallbackFunctions, LogSink};
use super::FmuInner;

mod extras;
mod values;

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
    /// `fmi2Instantiate`'s loggingOn (errors say whether the FMU was asked to log).
    logging_on: bool,
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
        echo: bool,
    ) -> Result<Instance, FmuError> {
        let failed = |reason: String, messages: Vec<LogMessage>| FmuError::InstantiateFailed {
            path: fmu.path.clone(),
            instance: instance_name.to_string(),
            reason,
            messages,
            logging_on,
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

        let sink = LogSink::new(echo);
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
            logging_on,
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

    /// [`Instance::call`] of the FMI function `function` (`pick` takes it from the API) whose
    /// only argument is the component.
    fn call_plain(
        &mut self,
        function: &'static str,
        pick: fn(&Functions) -> unsafe extern "C" fn(Component) -> RawStatus,
    ) -> Result<Status, FmuError> {
        self.call(function, |api, c| {
            // SAFETY: `c` is a live component.
            unsafe { pick(api)(c) }
        })
    }

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
            logging_on: self.logging_on,
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
        self.call_plain("fmi2EnterInitializationMode", |api| {
            api.enter_initialization_mode
        })?;
        self.state = InstanceState::InitializationMode;
        Ok(())
    }

    /// `fmi2ExitInitializationMode`: afterwards the instance steps.
    pub fn exit_initialization_mode(&mut self) -> Result<(), FmuError> {
        self.call_plain("fmi2ExitInitializationMode", |api| {
            api.exit_initialization_mode
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
        self.call_plain("fmi2CancelStep", |api| api.cancel_step)?;
        Ok(())
    }

    /// `fmi2Terminate`.
    pub fn terminate(&mut self) -> Result<(), FmuError> {
        self.call_plain("fmi2Terminate", |api| api.terminate)?;
        self.state = InstanceState::Terminated;
        Ok(())
    }

    /// `fmi2Reset`: back to the state after instantiation, with the start values.
    pub fn reset(&mut self) -> Result<(), FmuError> {
        self.call_plain("fmi2Reset", |api| api.reset)?;
        self.state = InstanceState::Instantiated;
        Ok(())
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
