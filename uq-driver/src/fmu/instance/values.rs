//! Setting and getting variable values: by value reference, and by name with the FMI 2.0
//! rules on what may be set when.

use std::ffi::{c_char, c_int};
use std::ptr;

use super::{c_string_arg, same_len, Instance, InstanceState};
use crate::fmu::binary::{c_string, Component, Functions, RawStatus, Vr};
use crate::fmu::description::ScalarVariable;
use crate::fmu::error::FmuError;

/// A `fmi2Set…` function: value references and as many values.
type SetFn<T> = unsafe extern "C" fn(Component, *const Vr, usize, *const T) -> RawStatus;
/// A `fmi2Get…` function: value references and room for as many values.
type GetFn<T> = unsafe extern "C" fn(Component, *const Vr, usize, *mut T) -> RawStatus;

impl Instance {
    /// Calls the setter `function` (`pick` takes it from the API; `what` names the method in
    /// errors) with `vrs` and as many `values`.
    fn set_values<T>(
        &mut self,
        what: &'static str,
        function: &'static str,
        pick: fn(&Functions) -> SetFn<T>,
        vrs: &[u32],
        values: &[T],
    ) -> Result<(), FmuError> {
        same_len(what, vrs.len(), values.len())?;
        self.call(function, |api, c| {
            // SAFETY: both arrays have `vrs.len()` elements.
            unsafe { pick(api)(c, vrs.as_ptr(), vrs.len(), values.as_ptr()) }
        })?;
        Ok(())
    }

    /// Calls the getter `function` (`pick` takes it from the API; `what` names the method in
    /// errors) with `vrs`, writing as many `values`.
    fn get_values<T>(
        &mut self,
        what: &'static str,
        function: &'static str,
        pick: fn(&Functions) -> GetFn<T>,
        vrs: &[u32],
        values: &mut [T],
    ) -> Result<(), FmuError> {
        same_len(what, vrs.len(), values.len())?;
        self.call(function, |api, c| {
            // SAFETY: both arrays have `vrs.len()` elements; the output is writable.
            unsafe { pick(api)(c, vrs.as_ptr(), vrs.len(), values.as_mut_ptr()) }
        })?;
        Ok(())
    }

    // ------------------------------------------------------------------------------------------
    // Values.

    /// `fmi2SetReal`.
    pub fn set_real(&mut self, vrs: &[u32], values: &[f64]) -> Result<(), FmuError> {
        self.set_values("set_real", "fmi2SetReal", |api| api.set_real, vrs, values)
    }

    /// `fmi2GetReal`.
    pub fn get_real(&mut self, vrs: &[u32], values: &mut [f64]) -> Result<(), FmuError> {
        self.get_values("get_real", "fmi2GetReal", |api| api.get_real, vrs, values)
    }

    /// `fmi2SetInteger` (also for Enumeration variables).
    pub fn set_integer(&mut self, vrs: &[u32], values: &[i32]) -> Result<(), FmuError> {
        self.set_values(
            "set_integer",
            "fmi2SetInteger",
            |api| api.set_integer,
            vrs,
            values,
        )
    }

    /// `fmi2GetInteger` (also for Enumeration variables).
    pub fn get_integer(&mut self, vrs: &[u32], values: &mut [i32]) -> Result<(), FmuError> {
        self.get_values(
            "get_integer",
            "fmi2GetInteger",
            |api| api.get_integer,
            vrs,
            values,
        )
    }

    /// `fmi2SetBoolean`.
    pub fn set_boolean(&mut self, vrs: &[u32], values: &[bool]) -> Result<(), FmuError> {
        same_len("set_boolean", vrs.len(), values.len())?;
        let raw: Vec<c_int> = values.iter().map(|&b| c_int::from(b)).collect();
        self.set_values(
            "set_boolean",
            "fmi2SetBoolean",
            |api| api.set_boolean,
            vrs,
            &raw,
        )
    }

    /// `fmi2GetBoolean`.
    pub fn get_boolean(&mut self, vrs: &[u32], values: &mut [bool]) -> Result<(), FmuError> {
        same_len("get_boolean", vrs.len(), values.len())?;
        let mut raw: Vec<c_int> = vec![0; vrs.len()];
        self.get_values(
            "get_boolean",
            "fmi2GetBoolean",
            |api| api.get_boolean,
            vrs,
            &mut raw,
        )?;
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
        self.get_values(
            "get_string",
            "fmi2GetString",
            |api| api.get_string,
            vrs,
            &mut raw,
        )?;
        for (v, &p) in values.iter_mut().zip(&raw) {
            // SAFETY: the FMU returned null or NUL-terminated strings valid until its next call.
            match unsafe { c_string(p) } {
                Some(s) => *v = s,
                None => return Err(self.protocol("fmi2GetString", "returned a null string")),
            }
        }
        Ok(())
    }

    /// The String variables of causality `calculatedParameter` (in description order) with
    /// their values: what an FMU computes at initialization to describe itself, such as the
    /// instruction set its solver picked on this machine. Read them after initialization.
    pub fn get_calculated_strings(&mut self) -> Result<Vec<(String, String)>, FmuError> {
        let (names, vrs): (Vec<String>, Vec<u32>) = self
            .description()
            .variables
            .iter()
            .filter(|v| v.is_calculated_string())
            .map(|v| (v.name.clone(), v.value_reference))
            .unzip();
        if vrs.is_empty() {
            return Ok(Vec::new());
        }
        let mut values = vec![String::new(); vrs.len()];
        self.get_string(&vrs, &mut values)?;
        Ok(names.into_iter().zip(values).collect())
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
}
