//! How a study's runs get their FMU instance: a fresh one (`fmi2FreeInstance` of the previous
//! one, then `fmi2Instantiate`), or the previous one reused through `fmi2Reset`, and the
//! self-check that decides between the two.
//!
//! Reuse saves an instantiation per run, but `fmi2Reset` is one of the least-tested functions
//! of FMUs from other tools: one that fails is replaced by a fresh instance (the run goes on, a
//! warning says so once), and one that returns OK but forgets start values would give silently
//! wrong numbers. So before a study reuses instances, its first point runs on a fresh instance
//! (the record stored), then again on the same instance after `fmi2Reset`; only when both
//! records agree bit for bit are instances reused. Otherwise (and with `--fresh-instances`, and
//! for a study with a single point to run) every run gets a fresh instance.
//!
//! Each instantiation has a name of its own, `uq-driver-<pid>-<n>`, unique on the host while
//! the process lives: FMI 2.0 makes `instanceName` the instance's identity, and FMUs key files
//! on it.

use std::sync::atomic::{AtomicU64, Ordering};

use serde::{Deserialize, Serialize};

use crate::fmu::{Fmu, FmuError, Instance, Status};

/// How runs get their FMU instance.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize, Deserialize)]
pub struct InstancePolicy {
    /// Reuse the previous run's instance through `fmi2Reset` (false: free it and instantiate
    /// afresh for every run).
    pub reuse: bool,
    /// `fmi2Instantiate`'s `loggingOn` (`--fmu-logging`): many FMUs send their messages, even
    /// at fmi2Error or fmi2Fatal, only then.
    pub logging_on: bool,
}

/// A name for a new instance, unique on the host while this process lives:
/// `uq-driver-<pid>-<n>`, n counting the instantiations of the process.
pub fn instance_name() -> String {
    static NEXT: AtomicU64 = AtomicU64::new(0);
    let n = NEXT.fetch_add(1, Ordering::Relaxed);
    format!("uq-driver-{}-{n}", std::process::id())
}

/// The instance of one worker (thread or process), if any, and how the next run gets one.
#[derive(Debug)]
pub struct Slot {
    inst: Option<Instance>,
    policy: InstancePolicy,
    /// Copy the FMU's messages to stderr as they come.
    echo: bool,
    /// Why `fmi2Reset` failed, when it did since the last [`Slot::take_reset_failure`] (the
    /// run then got a fresh instance).
    reset_failure: Option<String>,
}

impl Slot {
    /// An empty slot.
    pub fn new(policy: InstancePolicy, echo: bool) -> Slot {
        Slot {
            inst: None,
            policy,
            echo,
            reset_failure: None,
        }
    }

    /// Reuse instances from now on, or not.
    pub fn set_reuse(&mut self, reuse: bool) {
        self.policy.reuse = reuse;
    }

    /// The instance for a new run: the previous one after `fmi2Reset` when instances are reused
    /// and the reset succeeds, else a fresh one (the previous one freed first: an FMU that can
    /// be instantiated only once per process allows no overlap). A reset that fails other than
    /// by fmi2Fatal is noted ([`Slot::take_reset_failure`]) and replaced by a fresh instance.
    pub fn start(&mut self, fmu: &Fmu) -> Result<&mut Instance, FmuError> {
        if self.policy.reuse {
            if let Some(inst) = self.inst.as_mut() {
                match inst.reset() {
                    Ok(()) => return Ok(self.inst.as_mut().expect("present")),
                    Err(e) if fatal(&e) => return Err(e),
                    Err(e) => {
                        if self.reset_failure.is_none() {
                            self.reset_failure = Some(e.to_string());
                        }
                    }
                }
            }
        }
        self.inst = None;
        let name = instance_name();
        let inst = fmu.instantiate_with(&name, self.policy.logging_on, self.echo)?;
        Ok(self.inst.insert(inst))
    }

    /// The instance of the run in progress, if any.
    pub(crate) fn current(&mut self) -> Option<&mut Instance> {
        self.inst.as_mut()
    }

    /// Frees the instance (a failed run's may be in an error state).
    pub fn discard(&mut self) {
        self.inst = None;
    }

    /// Why `fmi2Reset` failed since the last call, if it did.
    pub fn take_reset_failure(&mut self) -> Option<String> {
        self.reset_failure.take()
    }
}

/// Whether `e` is fmi2Fatal or a call refused after one: no fresh instance can help.
fn fatal(e: &FmuError) -> bool {
    matches!(
        e,
        FmuError::Unusable { .. }
            | FmuError::Call {
                status: Status::Fatal,
                ..
            }
    )
}

/// Whether two records are the same bit for bit (any NaN equal to any NaN).
pub fn same_record(a: &[f64], b: &[f64]) -> bool {
    a.len() == b.len()
        && a.iter()
            .zip(b)
            .all(|(x, y)| x.to_bits() == y.to_bits() || (x.is_nan() && y.is_nan()))
}

/// The outcome of the reset self-check.
#[derive(Clone, Debug, PartialEq)]
pub enum ResetCheck {
    /// The record after `fmi2Reset` is the fresh instance's: instances are reused.
    Passed,
    /// It is not (or the reset or the run failed): every run gets a fresh instance. The text
    /// says what happened.
    Failed(String),
    /// The first run failed, so nothing could be compared: every run gets a fresh instance.
    NotRun,
}

impl ResetCheck {
    /// Whether instances are reused after this check.
    pub fn reuse(&self) -> bool {
        matches!(self, ResetCheck::Passed)
    }

    /// The warning to print and keep, if any, for the check at point `point`.
    pub fn warning(&self, point: usize) -> Option<String> {
        let ResetCheck::Failed(why) = self else {
            return None;
        };
        Some(format!(
            "{why} (reset self-check on point {point}: run on a fresh instance, then again \
             after fmi2Reset; the fresh instance's record is kept); every point now runs on a \
             fresh instance (fmi2FreeInstance, then fmi2Instantiate), as --fresh-instances asks"
        ))
    }
}

/// Where the second record differs from the first, for the warning.
pub fn first_difference(first: &[f64], second: &[f64]) -> String {
    if first.len() != second.len() {
        return format!(
            "the FMU's results after fmi2Reset differ from a fresh instance's: {} values \
             after fmi2Reset, {} on a fresh instance",
            second.len(),
            first.len()
        );
    }
    let k = first
        .iter()
        .zip(second)
        .position(|(x, y)| !same_record(&[*x], &[*y]))
        .unwrap_or(0);
    format!(
        "the FMU's results after fmi2Reset differ from a fresh instance's: value {k} of the \
         record is {} after fmi2Reset, {} on a fresh instance",
        second[k], first[k]
    )
}

/// The warning for a `fmi2Reset` that failed after the self-check had passed.
pub fn reset_failed_warning(why: &str) -> String {
    format!(
        "fmi2Reset failed ({why}); such runs get a fresh instance instead (fmi2FreeInstance, \
         then fmi2Instantiate), so no point fails for it (--fresh-instances never resets)"
    )
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn instance_names_are_unique_and_name_the_process() {
        let a = instance_name();
        let b = instance_name();
        assert_ne!(a, b);
        let prefix = format!("uq-driver-{}-", std::process::id());
        assert!(a.starts_with(&prefix) && b.starts_with(&prefix), "{a} {b}");
    }

    #[test]
    fn records_compare_bit_for_bit_with_nan_equal_to_nan() {
        let nan2 = f64::from_bits(f64::NAN.to_bits() ^ 1);
        assert!(same_record(&[1.0, f64::NAN], &[1.0, nan2]));
        assert!(!same_record(&[0.0], &[-0.0]));
        assert!(!same_record(&[1.0], &[1.0, 2.0]));
        assert!(!same_record(&[1.0], &[1.0 + f64::EPSILON]));
        assert_eq!(
            first_difference(&[1.0, 2.0], &[1.0, 3.0]),
            "the FMU's results after fmi2Reset differ from a fresh instance's: value 1 of the \
             record is 3 after fmi2Reset, 2 on a fresh instance"
        );
    }
}
