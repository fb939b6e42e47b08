//! The FMI 2.0 Co-Simulation state machine as a table: one bitmask of legal states per
//! function (after the FMI 2.0.4 specification, §4.2.4, and the Reference-FMUs).

/// The states of a Co-Simulation slave.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[repr(u32)]
pub enum State {
    /// After fmi2Instantiate or fmi2Reset.
    Instantiated = 1 << 0,
    /// Between fmi2EnterInitializationMode and fmi2ExitInitializationMode.
    InitializationMode = 1 << 1,
    /// Initialized and ready for fmi2DoStep.
    StepComplete = 1 << 2,
    /// An asynchronous step is running (never happens: steps are synchronous).
    StepInProgress = 1 << 3,
    /// A step failed with fmi2Discard.
    StepFailed = 1 << 4,
    /// A step was cancelled.
    StepCanceled = 1 << 5,
    /// After fmi2Terminate.
    Terminated = 1 << 6,
    /// After a function returned fmi2Error.
    Error = 1 << 7,
    /// After a function returned fmi2Fatal.
    Fatal = 1 << 8,
}

impl State {
    /// The name used in log messages.
    pub fn name(self) -> &'static str {
        match self {
            State::Instantiated => "Instantiated",
            State::InitializationMode => "InitializationMode",
            State::StepComplete => "StepComplete",
            State::StepInProgress => "StepInProgress",
            State::StepFailed => "StepFailed",
            State::StepCanceled => "StepCanceled",
            State::Terminated => "Terminated",
            State::Error => "Error",
            State::Fatal => "Fatal",
        }
    }

    /// The state as a bitmask bit.
    pub fn bit(self) -> u32 {
        self as u32
    }
}

/// The functions that take an instance (fmi2Instantiate, fmi2GetVersion and
/// fmi2GetTypesPlatform take none and are legal at any time).
#[allow(missing_docs)]
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Func {
    SetDebugLogging,
    FreeInstance,
    SetupExperiment,
    EnterInitializationMode,
    ExitInitializationMode,
    Terminate,
    Reset,
    GetValues,
    SetValues,
    FmuState,
    GetDirectionalDerivative,
    SetRealInputDerivatives,
    GetRealOutputDerivatives,
    DoStep,
    CancelStep,
    GetStatus,
}

use State::*;

const fn mask(states: &[State]) -> u32 {
    let mut m = 0;
    let mut i = 0;
    while i < states.len() {
        m |= states[i] as u32;
        i += 1;
    }
    m
}

const ALL_BUT_FATAL: u32 = mask(&[
    Instantiated,
    InitializationMode,
    StepComplete,
    StepInProgress,
    StepFailed,
    StepCanceled,
    Terminated,
    Error,
]);

const AFTER_INIT: u32 = mask(&[
    InitializationMode,
    StepComplete,
    StepFailed,
    StepCanceled,
    Terminated,
    Error,
]);

impl Func {
    /// The bitmask of states in which the function may be called.
    pub const fn allowed(self) -> u32 {
        match self {
            Func::SetDebugLogging => ALL_BUT_FATAL,
            // Freeing must be possible in every state, Fatal included, or the host leaks.
            Func::FreeInstance => ALL_BUT_FATAL & !(StepInProgress as u32) | Fatal as u32,
            Func::SetupExperiment => Instantiated as u32,
            Func::EnterInitializationMode => Instantiated as u32,
            Func::ExitInitializationMode => InitializationMode as u32,
            Func::Terminate => mask(&[StepComplete, StepFailed, StepCanceled, Error]),
            Func::Reset => ALL_BUT_FATAL & !(StepInProgress as u32),
            Func::GetValues => AFTER_INIT,
            Func::SetValues => mask(&[Instantiated, InitializationMode, StepComplete]),
            Func::FmuState => ALL_BUT_FATAL & !(StepInProgress as u32),
            Func::GetDirectionalDerivative => AFTER_INIT,
            Func::SetRealInputDerivatives => {
                mask(&[Instantiated, InitializationMode, StepComplete])
            }
            Func::GetRealOutputDerivatives => {
                mask(&[StepComplete, StepFailed, StepCanceled, Terminated, Error])
            }
            Func::DoStep => StepComplete as u32,
            Func::CancelStep => StepInProgress as u32,
            Func::GetStatus => mask(&[
                StepComplete,
                StepInProgress,
                StepFailed,
                StepCanceled,
                Terminated,
            ]),
        }
    }

    /// Whether the function may be called in `state`.
    pub fn allowed_in(self, state: State) -> bool {
        self.allowed() & state.bit() != 0
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn table_matches_the_standard_on_key_cases() {
        assert!(Func::DoStep.allowed_in(StepComplete));
        assert!(!Func::DoStep.allowed_in(Instantiated));
        assert!(!Func::DoStep.allowed_in(Terminated));
        assert!(!Func::GetValues.allowed_in(Instantiated));
        assert!(Func::GetValues.allowed_in(Error));
        assert!(Func::Reset.allowed_in(Error));
        assert!(!Func::Reset.allowed_in(Fatal));
        assert!(Func::FreeInstance.allowed_in(Fatal));
        assert!(!Func::SetupExperiment.allowed_in(StepComplete));
        assert!(!Func::ExitInitializationMode.allowed_in(Instantiated));
        assert!(!Func::SetValues.allowed_in(Terminated));
        assert!(!Func::Terminate.allowed_in(Terminated));
    }
}
