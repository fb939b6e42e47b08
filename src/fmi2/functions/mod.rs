//! The 34 exported FMI 2.0 Co-Simulation functions. This is the only file with
//! `extern "C"` entry points: each one null-checks its pointers, catches panics (a panic
//! becomes fmi2Fatal or a NULL instance, never an abort of the host) and hands safe Rust
//! values to [`Instance`].
#![allow(non_snake_case)]

use std::ffi::{c_char, CStr};
use std::panic::{catch_unwind, AssertUnwindSafe};

use crate::fmi2::instance::{Failure, Instance, Outcome, INSTANCE_MAGIC};
use crate::fmi2::logger::Category;
use crate::fmi2::state::Func;
use crate::fmi2::types::*;

/// Setting any Real to this value panics inside the FMU when the test hook is armed, to prove
/// the panic boundary of the very library that is shipped: the call returns fmi2Fatal and the
/// host goes on. Armed by the environment variable [`TEST_PANIC_ENV`] set to `1` in the process
/// that loads the FMU (read only when the value is seen), or always by the `test-panic`
/// feature. Unarmed, the value is an ordinary finite number.
pub const TEST_PANIC_VALUE: f64 = -7.0e77;

/// The environment variable that arms the test hook of [`TEST_PANIC_VALUE`].
pub const TEST_PANIC_ENV: &str = "RAILUQ_FMU_TEST_PANIC";

/// Whether the test hook of [`TEST_PANIC_VALUE`] is armed.
pub(super) fn test_panic_armed() -> bool {
    cfg!(feature = "test-panic") || std::env::var_os(TEST_PANIC_ENV).is_some_and(|v| v == "1")
}

pub(super) fn guard<R>(on_panic: R, f: impl FnOnce() -> R) -> R {
    catch_unwind(AssertUnwindSafe(f)).unwrap_or(on_panic)
}

pub(super) fn panic_message(p: &(dyn std::any::Any + Send)) -> String {
    p.downcast_ref::<&str>()
        .map(|s| s.to_string())
        .or_else(|| p.downcast_ref::<String>().cloned())
        .unwrap_or_else(|| "unknown panic".into())
}

/// Turns an `fmi2Component` into the instance it points to.
///
/// # Safety
/// `c` must be NULL or a pointer returned by [`fmi2Instantiate`] and not yet freed.
pub(super) unsafe fn instance_mut<'a>(c: Fmi2Component) -> Option<&'a mut Instance> {
    if c.is_null() || !(c as usize).is_multiple_of(std::mem::align_of::<Instance>()) {
        return None;
    }
    // SAFETY: `Instance` is repr(C) with the magic first: reading one u64 at a non-NULL, aligned
    // pointer from the importer checks it is ours before any reference is made.
    if unsafe { std::ptr::read(c as *const u64) } != INSTANCE_MAGIC {
        return None;
    }
    // SAFETY: the magic matches, so `c` is a live Box<Instance> made by fmi2Instantiate.
    Some(unsafe { &mut *(c as *mut Instance) })
}

/// A slice from a C array, or None when the pointer is NULL.
///
/// # Safety
/// If non-NULL, `p` must point to `n` valid, initialized values.
pub(super) unsafe fn slice<'a, T>(p: *const T, n: usize) -> Option<&'a [T]> {
    if p.is_null() {
        None
    } else {
        // SAFETY: non-NULL and, by the caller's contract, `n` valid elements.
        Some(unsafe { std::slice::from_raw_parts(p, n) })
    }
}

/// A mutable slice from a C array, or None when the pointer is NULL.
///
/// # Safety
/// If non-NULL, `p` must point to `n` writable values.
pub(super) unsafe fn slice_mut<'a, T>(p: *mut T, n: usize) -> Option<&'a mut [T]> {
    if p.is_null() {
        None
    } else {
        // SAFETY: non-NULL and, by the caller's contract, `n` writable elements.
        Some(unsafe { std::slice::from_raw_parts_mut(p, n) })
    }
}

/// A Rust string from a C string, or None when NULL or not UTF-8.
///
/// # Safety
/// If non-NULL, `p` must be a NUL-terminated string.
pub(super) unsafe fn c_str<'a>(p: *const c_char) -> Option<&'a str> {
    if p.is_null() {
        None
    } else {
        // SAFETY: non-NULL and NUL-terminated by the caller's contract.
        unsafe { CStr::from_ptr(p) }.to_str().ok()
    }
}

pub(super) fn null_arg(name: &str) -> Failure {
    Failure::error(format!("argument '{name}' is NULL"))
}

/// Runs `body` on the instance behind `c` after the state-table check, inside a panic
/// boundary. Failures are logged and move the instance to Error or Fatal.
pub(super) fn with_instance(
    c: Fmi2Component,
    func: Func,
    fname: &'static str,
    body: impl FnOnce(&mut Instance) -> Outcome,
) -> Fmi2Status {
    guard(FMI2_FATAL, || {
        // SAFETY: the FMI standard requires `c` to be an instance returned by fmi2Instantiate;
        // NULL, misaligned and freed (magic cleared) pointers are rejected inside.
        let Some(inst) = (unsafe { instance_mut(c) }) else {
            return FMI2_ERROR;
        };
        if let Err(f) = inst.check_state(func, fname) {
            return inst.fail(fname, f);
        }
        match catch_unwind(AssertUnwindSafe(|| body(&mut *inst))) {
            Ok(Ok(status)) => {
                if inst.logger.would_log(FMI2_OK, Category::Calls) {
                    inst.logger
                        .log(FMI2_OK, Category::Calls, &format!("{fname}: ok"));
                }
                status
            }
            Ok(Err(f)) => inst.fail(fname, f),
            Err(p) => {
                let msg = format!("internal error (panic): {}", panic_message(p.as_ref()));
                inst.fail(
                    fname,
                    Failure {
                        status: FMI2_FATAL,
                        message: msg,
                    },
                )
            }
        }
    })
}

mod fmu_state;
mod lifecycle;
mod step;
mod values;
