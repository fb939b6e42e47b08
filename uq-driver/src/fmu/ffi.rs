//! Conversions at the C boundary shared by the library loader, the instances and the logger.

use std::ffi::{c_char, CStr};

/// Copies a C string returned by the FMU, `None` if null.
///
/// # Safety
/// `ptr` must be null or point to a NUL-terminated string valid for the duration of the call.
pub(crate) unsafe fn c_string(ptr: *const c_char) -> Option<String> {
    if ptr.is_null() {
        return None;
    }
    // SAFETY: non-null, and NUL-terminated and valid per this function's contract.
    let s = unsafe { CStr::from_ptr(ptr) };
    Some(s.to_string_lossy().into_owned())
}
