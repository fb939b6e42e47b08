//! Optional FMI 2.0 Co-Simulation capabilities: directional and input/output derivatives,
//! status queries and FMU states (get, set, free, serialize).

use std::ffi::c_int;
use std::ptr;

use super::{same_len, FmuState, Instance, InstanceState, StatusKind};
use crate::fmu::binary::c_string;
use crate::fmu::binary::{Component, Functions, RawStatus, StatePtr};
use crate::fmu::error::{FmuError, Status};
use crate::fmu::logger::LogSink;

/// A `fmi2Get…Status` function: the kind of status and where to write it.
type StatusFn<T> = unsafe extern "C" fn(Component, c_int, *mut T) -> RawStatus;

impl Instance {
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

    /// Calls the status query `function` (`pick` takes it from the API) for `kind`, the FMU
    /// writing over `value`.
    fn status<T>(
        &mut self,
        function: &'static str,
        pick: fn(&Functions) -> StatusFn<T>,
        kind: StatusKind,
        mut value: T,
    ) -> Result<T, FmuError> {
        self.call(function, |api, c| {
            // SAFETY: `value` is writable.
            unsafe { pick(api)(c, kind as c_int, &mut value) }
        })?;
        Ok(value)
    }

    /// `fmi2GetStatus`.
    pub fn get_status(&mut self, kind: StatusKind) -> Result<Status, FmuError> {
        let value = self.status("fmi2GetStatus", |api| api.get_status, kind, 0)?;
        Ok(Status::from_raw(value))
    }

    /// `fmi2GetRealStatus` (e.g. [`StatusKind::LastSuccessfulTime`], in s).
    pub fn get_real_status(&mut self, kind: StatusKind) -> Result<f64, FmuError> {
        self.status("fmi2GetRealStatus", |api| api.get_real_status, kind, 0.0)
    }

    /// `fmi2GetIntegerStatus`.
    pub fn get_integer_status(&mut self, kind: StatusKind) -> Result<i32, FmuError> {
        self.status(
            "fmi2GetIntegerStatus",
            |api| api.get_integer_status,
            kind,
            0,
        )
    }

    /// `fmi2GetBooleanStatus` (e.g. [`StatusKind::Terminated`]).
    pub fn get_boolean_status(&mut self, kind: StatusKind) -> Result<bool, FmuError> {
        let value = self.status(
            "fmi2GetBooleanStatus",
            |api| api.get_boolean_status,
            kind,
            0,
        )?;
        Ok(value != 0)
    }

    /// `fmi2GetStringStatus` (e.g. [`StatusKind::PendingStatus`]).
    pub fn get_string_status(&mut self, kind: StatusKind) -> Result<String, FmuError> {
        let value = self.status(
            "fmi2GetStringStatus",
            |api| api.get_string_status,
            kind,
            ptr::null(),
        )?;
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
