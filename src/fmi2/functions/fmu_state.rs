//! FMU state: get, set, free, serialize and deserialize.

use crate::fmi2::instance::{Failure, Snapshot, SNAPSHOT_MAGIC};
use crate::fmi2::state::Func;
use crate::fmi2::types::*;

use super::*;

// ---------------------------------------------------------------- FMU state

/// fmi2GetFMUstate: allocates a snapshot, or overwrites `*state` if it is one.
///
/// # Safety
/// FMI 2.0 contract: `c` from fmi2Instantiate; `state` points to NULL or a snapshot of ours.
#[no_mangle]
pub unsafe extern "C" fn fmi2GetFMUstate(c: Fmi2Component, state: *mut Fmi2FmuState) -> Fmi2Status {
    with_instance(c, Func::FmuState, "fmi2GetFMUstate", |inst| {
        if state.is_null() {
            return Err(null_arg("FMUstate"));
        }
        let snap = inst.snapshot();
        // SAFETY: `state` is non-NULL and points to a writable fmi2FMUstate (FMI contract).
        let slot = unsafe { &mut *state };
        // SAFETY: `*slot` is NULL or a snapshot we allocated (checked by its magic).
        match unsafe { snapshot_mut(*slot) } {
            Some(existing) => *existing = snap,
            None if slot.is_null() => *slot = Box::into_raw(Box::new(snap)) as Fmi2FmuState,
            None => return Err(Failure::error("*FMUstate is not an FMU state of this FMU")),
        }
        Ok(FMI2_OK)
    })
}

/// Turns an fmi2FMUstate into our snapshot.
///
/// # Safety
/// `s` must be NULL or a pointer we returned from fmi2GetFMUstate/fmi2DeSerializeFMUstate.
unsafe fn snapshot_mut<'a>(s: Fmi2FmuState) -> Option<&'a mut Snapshot> {
    if s.is_null() || !(s as usize).is_multiple_of(std::mem::align_of::<Snapshot>()) {
        return None;
    }
    // SAFETY: `Snapshot` is repr(C) with the magic first; read it before making a reference.
    if unsafe { std::ptr::read(s as *const u64) } != SNAPSHOT_MAGIC {
        return None;
    }
    // SAFETY: the magic matches, so `s` is a live Box<Snapshot> we allocated.
    Some(unsafe { &mut *(s as *mut Snapshot) })
}

/// fmi2SetFMUstate.
///
/// # Safety
/// FMI 2.0 contract: `c` from fmi2Instantiate; `state` from fmi2GetFMUstate.
#[no_mangle]
pub unsafe extern "C" fn fmi2SetFMUstate(c: Fmi2Component, state: Fmi2FmuState) -> Fmi2Status {
    with_instance(c, Func::FmuState, "fmi2SetFMUstate", |inst| {
        // SAFETY: FMI contract; foreign pointers are rejected by the magic check.
        let snap = unsafe { snapshot_mut(state) }
            .ok_or_else(|| Failure::error("FMUstate is NULL or not an FMU state of this FMU"))?;
        inst.restore(snap)
    })
}

/// fmi2FreeFMUstate: frees `*state` and sets it to NULL.
///
/// # Safety
/// FMI 2.0 contract: `c` from fmi2Instantiate; `state` points to a snapshot pointer or NULL.
#[no_mangle]
pub unsafe extern "C" fn fmi2FreeFMUstate(
    c: Fmi2Component,
    state: *mut Fmi2FmuState,
) -> Fmi2Status {
    with_instance(c, Func::FmuState, "fmi2FreeFMUstate", |_inst| {
        if state.is_null() {
            return Ok(FMI2_OK);
        }
        // SAFETY: non-NULL pointer to the importer's fmi2FMUstate variable.
        let slot = unsafe { &mut *state };
        if slot.is_null() {
            return Ok(FMI2_OK);
        }
        // SAFETY: checked by magic; allocated by Box::into_raw in fmi2GetFMUstate.
        let snap = unsafe { snapshot_mut(*slot) }
            .ok_or_else(|| Failure::error("*FMUstate is not an FMU state of this FMU"))?;
        snap.magic = 0;
        // SAFETY: a Box<Snapshot> we created, freed exactly once (the slot is cleared).
        drop(unsafe { Box::from_raw(*slot as *mut Snapshot) });
        *slot = std::ptr::null_mut();
        Ok(FMI2_OK)
    })
}

/// fmi2SerializedFMUstateSize.
///
/// # Safety
/// FMI 2.0 contract: `c` from fmi2Instantiate; `state` a snapshot; `size` writable.
#[no_mangle]
pub unsafe extern "C" fn fmi2SerializedFMUstateSize(
    c: Fmi2Component,
    state: Fmi2FmuState,
    size: *mut usize,
) -> Fmi2Status {
    with_instance(c, Func::FmuState, "fmi2SerializedFMUstateSize", |inst| {
        // SAFETY: FMI contract; checked by magic.
        let snap = unsafe { snapshot_mut(state) }
            .ok_or_else(|| Failure::error("FMUstate is NULL or not an FMU state of this FMU"))?;
        if size.is_null() {
            return Err(null_arg("size"));
        }
        let n = inst.serialize(snap).len();
        // SAFETY: non-NULL writable size_t (FMI contract).
        unsafe { *size = n };
        Ok(FMI2_OK)
    })
}

/// fmi2SerializeFMUstate.
///
/// # Safety
/// FMI 2.0 contract: `bytes` has room for `size` bytes.
#[no_mangle]
pub unsafe extern "C" fn fmi2SerializeFMUstate(
    c: Fmi2Component,
    state: Fmi2FmuState,
    bytes: *mut Fmi2Byte,
    size: usize,
) -> Fmi2Status {
    with_instance(c, Func::FmuState, "fmi2SerializeFMUstate", |inst| {
        // SAFETY: FMI contract; checked by magic.
        let snap = unsafe { snapshot_mut(state) }
            .ok_or_else(|| Failure::error("FMUstate is NULL or not an FMU state of this FMU"))?;
        let data = inst.serialize(snap);
        if data.len() != size {
            return Err(Failure::error(format!(
                "size {size} given, the serialized state has {} bytes",
                data.len()
            )));
        }
        // SAFETY: FMI contract: `bytes` has room for `size` bytes.
        let out = unsafe { slice_mut(bytes as *mut u8, size) }
            .ok_or_else(|| null_arg("serializedState"))?;
        out.copy_from_slice(&data);
        Ok(FMI2_OK)
    })
}

/// fmi2DeSerializeFMUstate: checks magic, version, model and checksum.
///
/// # Safety
/// FMI 2.0 contract: `bytes` holds `size` bytes; `state` writable.
#[no_mangle]
pub unsafe extern "C" fn fmi2DeSerializeFMUstate(
    c: Fmi2Component,
    bytes: *const Fmi2Byte,
    size: usize,
    state: *mut Fmi2FmuState,
) -> Fmi2Status {
    with_instance(c, Func::FmuState, "fmi2DeSerializeFMUstate", |inst| {
        // SAFETY: FMI contract: `size` readable bytes.
        let data = unsafe { slice(bytes as *const u8, size) }
            .ok_or_else(|| null_arg("serializedState"))?;
        if state.is_null() {
            return Err(null_arg("FMUstate"));
        }
        let snap = inst.deserialize(data)?;
        // SAFETY: non-NULL pointer to the importer's fmi2FMUstate variable.
        let slot = unsafe { &mut *state };
        // SAFETY: NULL or one of our snapshots (checked by magic).
        match unsafe { snapshot_mut(*slot) } {
            Some(existing) => *existing = snap,
            None => *slot = Box::into_raw(Box::new(snap)) as Fmi2FmuState,
        }
        Ok(FMI2_OK)
    })
}
