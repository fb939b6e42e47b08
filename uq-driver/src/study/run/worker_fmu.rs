//! The FMU each worker thread of the runner instantiates.
//!
//! Most FMUs serve every worker from one loaded library. An FMU that declares
//! `canBeInstantiatedOnlyOncePerProcess="true"` keeps state in its library's globals, so two
//! of its instances must never share one copy of the library: each worker thread then gets a
//! [`Fmu::private_copy`] of its own, loaded the first time the thread needs it. Runs are thus
//! in parallel and give the same numbers as on one thread.

use std::sync::{Mutex, PoisonError};

use crate::fmu::{Fmu, FmuError};

/// The FMU for each worker thread of a pool of `threads`.
pub(crate) struct WorkerFmus<'a> {
    shared: &'a Fmu,
    /// One slot per pool thread, filled on first use; `None` when the library may be shared.
    copies: Option<Vec<Mutex<Option<Fmu>>>>,
}

impl<'a> WorkerFmus<'a> {
    /// Workers of a pool of `threads` threads running `fmu`.
    pub(crate) fn new(fmu: &'a Fmu, threads: usize) -> WorkerFmus<'a> {
        let once = fmu
            .description()
            .co_simulation
            .can_be_instantiated_only_once_per_process;
        WorkerFmus {
            shared: fmu,
            copies: once.then(|| (0..threads.max(1)).map(|_| Mutex::new(None)).collect()),
        }
    }

    /// The FMU the calling thread instantiates: the shared one, or the thread's own copy
    /// (a thread outside the pool uses the first).
    pub(crate) fn current(&self) -> Result<Fmu, FmuError> {
        let Some(copies) = &self.copies else {
            return Ok(self.shared.clone());
        };
        let k = rayon::current_thread_index().unwrap_or(0) % copies.len();
        let mut slot = copies[k].lock().unwrap_or_else(PoisonError::into_inner);
        if let Some(fmu) = slot.as_ref() {
            return Ok(fmu.clone());
        }
        let fmu = self.shared.private_copy()?;
        *slot = Some(fmu.clone());
        Ok(fmu)
    }
}
