//! One FMU instance: the state machine, the model, the logger. Everything here is safe Rust;
//! the C boundary (pointer checks, panics) is in `functions.rs`.

use std::path::PathBuf;

use super::logger::{Category, Logger};
use super::state::{Func, State};
use super::types::*;
use crate::models::{
    Causality, InitContext, Model, ModelEntry, ModelError, SetResult, StateReader, StateWriter,
    VarType, Variability, Variable,
};

/// Marks a live instance (checked on every call, cleared on free).
pub const INSTANCE_MAGIC: u64 = 0x7261_696c_7571_4932;
/// Marks a live FMU state snapshot.
pub const SNAPSHOT_MAGIC: u64 = 0x7261_696c_7571_5353;
/// First bytes of a serialized FMU state.
pub const SERIAL_MAGIC: &[u8; 8] = b"RAILUQFS";
/// Version of the serialized FMU state layout.
pub const SERIAL_VERSION: u32 = 1;

/// Relative tolerance when comparing communication points.
pub const TIME_TOLERANCE: f64 = 1e-9;

/// A failed call: the status to return and the message to log.
#[derive(Debug, Clone, PartialEq)]
pub struct Failure {
    /// fmi2Warning is never a failure; fmi2Discard, fmi2Error or fmi2Fatal.
    pub status: Fmi2Status,
    /// What went wrong, for the log.
    pub message: String,
}

impl Failure {
    /// An fmi2Error with a message.
    pub fn error(message: impl Into<String>) -> Self {
        Failure {
            status: FMI2_ERROR,
            message: message.into(),
        }
    }
    /// An fmi2Discard with a message.
    pub fn discard(message: impl Into<String>) -> Self {
        Failure {
            status: FMI2_DISCARD,
            message: message.into(),
        }
    }
}

impl From<ModelError> for Failure {
    fn from(e: ModelError) -> Self {
        Failure::error(e.to_string())
    }
}

/// What a successful call returns: fmi2OK or fmi2Warning.
pub type Outcome = Result<Fmi2Status, Failure>;

/// A snapshot for fmi2GetFMUstate / fmi2SetFMUstate (repr(C): the magic comes first, so the
/// C boundary can check it before making a reference).
#[derive(Debug)]
#[repr(C)]
pub struct Snapshot {
    /// [`SNAPSHOT_MAGIC`] while alive.
    pub magic: u64,
    model: Box<dyn Model>,
    state: State,
    time: f64,
    start_time: f64,
    stop_time: Option<f64>,
    dirty: bool,
}

/// One FMU instance (repr(C): the magic comes first, so the C boundary can check it before
/// making a reference).
#[derive(Debug)]
#[repr(C)]
pub struct Instance {
    /// [`INSTANCE_MAGIC`] while alive.
    pub magic: u64,
    /// Instance name given by the importer.
    pub name: String,
    /// Logger and debug-logging settings.
    pub logger: Logger,
    /// Current state.
    pub state: State,
    entry: &'static ModelEntry,
    model: Box<dyn Model>,
    time: f64,
    start_time: f64,
    stop_time: Option<f64>,
    /// Parameters changed since the last initialization.
    dirty: bool,
    resource_dir: Option<PathBuf>,
    /// Strings returned by fmi2GetString, valid until the next call.
    pub strings: Vec<std::ffi::CString>,
}

impl Instance {
    /// A new instance of `entry` in state Instantiated.
    pub fn new(
        entry: &'static ModelEntry,
        name: String,
        logger: Logger,
        resource_dir: Option<PathBuf>,
    ) -> Self {
        Instance {
            magic: INSTANCE_MAGIC,
            name,
            logger,
            state: State::Instantiated,
            entry,
            model: (entry.create)(),
            time: 0.0,
            start_time: 0.0,
            stop_time: None,
            dirty: true,
            resource_dir,
            strings: Vec::new(),
        }
    }

    /// The model's name (FMU model identifier).
    pub fn model_name(&self) -> &'static str {
        self.entry.info.name
    }

    /// Current simulation time (s).
    pub fn time(&self) -> f64 {
        self.time
    }

    /// Checks the state table for `func`.
    pub fn check_state(&self, func: Func, fname: &str) -> Result<(), Failure> {
        if func.allowed_in(self.state) {
            Ok(())
        } else {
            Err(Failure::error(format!(
                "{fname} is not allowed in state {}",
                self.state.name()
            )))
        }
    }

    /// Records a failed call: logs it and moves to Error or Fatal as the standard says.
    pub fn fail(&mut self, fname: &str, f: Failure) -> Fmi2Status {
        self.logger.log(
            f.status,
            Category::of_status(f.status),
            &format!("{fname}: {}", f.message),
        );
        match f.status {
            FMI2_FATAL => self.state = State::Fatal,
            FMI2_ERROR if self.state != State::Fatal => self.state = State::Error,
            _ => {}
        }
        f.status
    }

    fn warn(&self, message: &str) -> Fmi2Status {
        self.logger.log(FMI2_WARNING, Category::Warning, message);
        FMI2_WARNING
    }

    fn ctx(&self) -> InitContext {
        InitContext {
            start_time: self.start_time,
            resource_dir: self.resource_dir.clone(),
        }
    }

    fn initialize_if_dirty(&mut self) -> Result<(), Failure> {
        if self.dirty {
            let ctx = self.ctx();
            self.model.initialize(&ctx)?;
            self.dirty = false;
        }
        Ok(())
    }

    /// fmi2SetupExperiment.
    pub fn setup_experiment(&mut self, start: f64, stop: Option<f64>) -> Outcome {
        if !start.is_finite() {
            return Err(Failure::error(format!("start time {start} is not finite")));
        }
        if let Some(stop) = stop {
            if !stop.is_finite() || stop < start {
                return Err(Failure::error(format!(
                    "stop time {stop} is not finite or before the start time {start}"
                )));
            }
        }
        self.start_time = start;
        self.time = start;
        self.stop_time = stop;
        self.dirty = true;
        Ok(FMI2_OK)
    }

    /// fmi2EnterInitializationMode.
    pub fn enter_initialization_mode(&mut self) -> Outcome {
        self.time = self.start_time;
        self.dirty = true;
        self.initialize_if_dirty()?;
        self.state = State::InitializationMode;
        Ok(FMI2_OK)
    }

    /// fmi2ExitInitializationMode.
    pub fn exit_initialization_mode(&mut self) -> Outcome {
        self.initialize_if_dirty()?;
        self.state = State::StepComplete;
        Ok(FMI2_OK)
    }

    /// fmi2Terminate.
    pub fn terminate(&mut self) -> Outcome {
        self.state = State::Terminated;
        Ok(FMI2_OK)
    }

    /// fmi2Reset: back to Instantiated with the start values.
    pub fn reset(&mut self) -> Outcome {
        self.model = (self.entry.create)();
        self.state = State::Instantiated;
        self.time = 0.0;
        self.start_time = 0.0;
        self.stop_time = None;
        self.dirty = true;
        Ok(FMI2_OK)
    }

    /// Finds a variable of type `ty` by value reference.
    pub fn lookup(&self, vr: u32, ty: VarType) -> Result<&'static Variable, Failure> {
        let info = self.entry.info;
        let var = info.variable(vr).ok_or_else(|| {
            Failure::error(format!(
                "unknown value reference {vr}: model {} has no such variable",
                info.name
            ))
        })?;
        if var.var_type() != ty {
            return Err(Failure::error(format!(
                "value reference {vr} ('{}') is a {:?} variable, not {ty:?}",
                var.name,
                var.var_type()
            )));
        }
        Ok(var)
    }

    fn check_settable(&self, var: &Variable) -> Result<(), Failure> {
        let before_init = matches!(self.state, State::Instantiated | State::InitializationMode);
        let ok = match (var.causality, var.variability) {
            (_, Variability::Constant) => false,
            (Causality::Parameter, Variability::Fixed) => before_init,
            (Causality::Parameter, Variability::Tunable) => true,
            (Causality::Input, _) => true,
            _ => false,
        };
        if ok {
            return Ok(());
        }
        let why = match (var.causality, var.variability) {
            (_, Variability::Constant) => "it is a constant".to_string(),
            (Causality::Parameter, Variability::Fixed) => format!(
                "it is a fixed parameter, settable only before fmi2ExitInitializationMode (state is {})",
                self.state.name()
            ),
            (c, _) => format!("its causality is {c:?}"),
        };
        Err(Failure::error(format!("cannot set '{}': {why}", var.name)))
    }

    /// Sets values of one type: every reference is checked, then each is set in order (a
    /// value refused by the model leaves the earlier ones of the same call set, and the
    /// instance in Error state).
    pub fn set_values<T: Copy + std::fmt::Debug>(
        &mut self,
        vrs: &[u32],
        values: &[T],
        ty: VarType,
        set: impl Fn(&mut dyn Model, u32, T) -> SetResult,
    ) -> Outcome {
        for &vr in vrs {
            let var = self.lookup(vr, ty)?;
            self.check_settable(var)?;
        }
        let mut status = FMI2_OK;
        for (&vr, &v) in vrs.iter().zip(values) {
            let warning = set(self.model.as_mut(), vr, v)?;
            if let Some(w) = warning {
                status = self.warn(&w);
            }
        }
        if matches!(self.state, State::Instantiated | State::InitializationMode) {
            self.dirty = true;
        }
        Ok(status)
    }

    /// Gets values of one type into `out` (untouched if any reference is unknown or of
    /// another type).
    pub fn get_values<T: Copy>(
        &mut self,
        vrs: &[u32],
        out: &mut [T],
        ty: VarType,
        get: impl Fn(&dyn Model, u32) -> Result<T, ModelError>,
    ) -> Outcome {
        if self.state == State::InitializationMode {
            self.initialize_if_dirty()?;
        }
        // Check every reference first, so that a bad one leaves `out` untouched; a checked
        // reference cannot fail to read. No allocation: this runs at every communication step.
        for &vr in vrs {
            self.lookup(vr, ty)?;
        }
        for (o, &vr) in out.iter_mut().zip(vrs) {
            *o = get(self.model.as_ref(), vr)?;
        }
        Ok(FMI2_OK)
    }

    /// Reads strings for fmi2GetString; the caller turns them into C strings.
    pub fn get_strings(&mut self, vrs: &[u32]) -> Result<Vec<String>, Failure> {
        if self.state == State::InitializationMode {
            self.initialize_if_dirty()?;
        }
        vrs.iter()
            .map(|&vr| {
                self.lookup(vr, VarType::String)?;
                Ok(self.model.get_string(vr)?)
            })
            .collect()
    }

    /// fmi2DoStep.
    pub fn do_step(&mut self, current: f64, h: f64) -> Outcome {
        if !(h.is_finite() && h > 0.0) {
            return Err(Failure::error(format!(
                "communication step size {h} must be finite and > 0"
            )));
        }
        if !current.is_finite() {
            return Err(Failure::error(format!(
                "communication point {current} is not finite"
            )));
        }
        let tol = TIME_TOLERANCE * self.time.abs().max(1.0);
        if (current - self.time).abs() > tol {
            return Err(Failure::error(format!(
                "communication point {current} does not match the FMU time {}",
                self.time
            )));
        }
        if let Some(stop) = self.stop_time {
            if current + h > stop + TIME_TOLERANCE * stop.abs().max(1.0) {
                return Err(Failure::error(format!(
                    "step to {} would pass the stop time {stop}",
                    current + h
                )));
            }
        }
        match self.model.do_step(current, h) {
            Ok(()) => {}
            Err(e @ ModelError::EndOfSimulation { .. }) => {
                // fmi2Discard with fmi2Terminated: the time stays at `current`, where the
                // outputs are valid; only status queries, getters, reset, terminate and free
                // are allowed now (FMI 2.0 slaveStepFailed).
                self.state = State::StepFailed;
                return Err(Failure::discard(format!(
                    "{e}; fmi2Terminated is true, fmi2LastSuccessfulTime = {current}"
                )));
            }
            Err(e) => return Err(e.into()),
        }
        self.time = current + h;
        Ok(FMI2_OK)
    }

    /// fmi2GetFMUstate into a new or existing snapshot.
    pub fn snapshot(&self) -> Snapshot {
        Snapshot {
            magic: SNAPSHOT_MAGIC,
            model: self.model.clone_box(),
            state: self.state,
            time: self.time,
            start_time: self.start_time,
            stop_time: self.stop_time,
            dirty: self.dirty,
        }
    }

    /// fmi2SetFMUstate.
    pub fn restore(&mut self, s: &Snapshot) -> Outcome {
        if s.model.info().name != self.entry.info.name {
            return Err(Failure::error(format!(
                "FMU state belongs to model {}, not {}",
                s.model.info().name,
                self.entry.info.name
            )));
        }
        self.model = s.model.clone_box();
        self.state = match s.state {
            State::Error | State::Fatal => State::StepComplete,
            st => st,
        };
        self.time = s.time;
        self.start_time = s.start_time;
        self.stop_time = s.stop_time;
        self.dirty = s.dirty;
        Ok(FMI2_OK)
    }

    /// Serialized form of a snapshot (see [`SERIAL_MAGIC`]).
    pub fn serialize(&self, s: &Snapshot) -> Vec<u8> {
        let mut w = StateWriter::default();
        w.bytes.extend_from_slice(SERIAL_MAGIC);
        w.bytes.extend_from_slice(&SERIAL_VERSION.to_le_bytes());
        w.str(s.model.info().name);
        w.u64(u64::from(s.state.bit()));
        w.f64(s.time);
        w.f64(s.start_time);
        w.u64(u64::from(s.stop_time.is_some()));
        w.f64(s.stop_time.unwrap_or(0.0));
        w.u64(u64::from(s.dirty));
        let mut m = StateWriter::default();
        s.model.save(&mut m);
        w.u64(m.bytes.len() as u64);
        w.bytes.extend_from_slice(&m.bytes);
        let sum = fnv1a64(&w.bytes);
        w.u64(sum);
        w.bytes
    }

    /// Parses a serialized snapshot, checking magic, version, model, length and checksum.
    pub fn deserialize(&self, bytes: &[u8]) -> Result<Snapshot, Failure> {
        let bad = |why: &str| Failure::error(format!("cannot deserialize FMU state: {why}"));
        if bytes.len() < SERIAL_MAGIC.len() + 4 + 8 || &bytes[..8] != SERIAL_MAGIC {
            return Err(bad("not a railuq FMU state (wrong magic or too short)"));
        }
        let version = u32::from_le_bytes(bytes[8..12].try_into().expect("4 bytes"));
        if version != SERIAL_VERSION {
            return Err(bad(&format!(
                "layout version {version}, this FMU reads version {SERIAL_VERSION}"
            )));
        }
        let (body, tail) = bytes.split_at(bytes.len() - 8);
        let sum = u64::from_le_bytes(tail.try_into().expect("8 bytes"));
        if fnv1a64(body) != sum {
            return Err(bad("checksum mismatch (truncated or corrupted)"));
        }
        let mut r = StateReader::new(&body[12..]);
        let name = r.str().map_err(|e| bad(&e.to_string()))?;
        if name != self.entry.info.name {
            return Err(bad(&format!(
                "state of model {name}, this instance is {}",
                self.entry.info.name
            )));
        }
        let parse = |r: &mut StateReader<'_>| -> Result<Snapshot, ModelError> {
            let bits = r.u64()? as u32;
            let state = [
                State::Instantiated,
                State::InitializationMode,
                State::StepComplete,
                State::StepFailed,
                State::StepCanceled,
                State::Terminated,
                State::Error,
            ]
            .into_iter()
            .find(|s| s.bit() == bits)
            .ok_or_else(|| ModelError::CorruptState(format!("unknown state {bits}")))?;
            let time = r.f64()?;
            let start_time = r.f64()?;
            let has_stop = r.u64()? != 0;
            let stop = r.f64()?;
            let dirty = r.u64()? != 0;
            let len = r.u64()? as usize;
            if len != r.remaining() {
                return Err(ModelError::CorruptState("model payload length".into()));
            }
            let mut model = (self.entry.create)();
            model.restore(r)?;
            if r.remaining() != 0 {
                return Err(ModelError::CorruptState("trailing bytes".into()));
            }
            Ok(Snapshot {
                magic: SNAPSHOT_MAGIC,
                model,
                state,
                time,
                start_time,
                stop_time: has_stop.then_some(stop),
                dirty,
            })
        };
        parse(&mut r).map_err(|e| bad(&e.to_string()))
    }
}

/// 64-bit FNV-1a hash (checksum of serialized states; stable across platforms).
pub fn fnv1a64(bytes: &[u8]) -> u64 {
    let mut h: u64 = 0xcbf2_9ce4_8422_2325;
    for b in bytes {
        h ^= u64::from(*b);
        h = h.wrapping_mul(0x0000_0100_0000_01b3);
    }
    h
}
