//! Errors of the reliability methods.

/// Why an evaluation stopped a method (as opposed to a failed run).
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
pub enum Abort {
    /// The caller stopped (Ctrl-C, a budget, an FMU that cannot be loaded).
    #[error("evaluation interrupted: {0}")]
    Interrupted(String),
    /// A stored run was at another point than the one now requested: the settings, the
    /// seed, the model's values or the code changed since the runs were stored.
    #[error(
        "stored run {run} was at u = {stored:?} but u = {requested:?} is requested now; \
         the stored runs belong to another study (settings, seed, model's values or \
         uq-driver's version): run it with --fresh, or into another --out"
    )]
    ReplayMismatch {
        /// The run index.
        run: u64,
        /// The stored point.
        stored: Vec<f64>,
        /// The point requested.
        requested: Vec<f64>,
    },
}

/// Why a reliability method stopped without a result.
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
pub enum ReliabilityError {
    /// The settings do not make sense (e.g. `p0` outside (0, 1), no samples).
    #[error("invalid settings: {0}")]
    Invalid(String),
    /// The model has no input.
    #[error("the model has no random input")]
    NoInputs,
    /// A run failed (or gave a value that is not finite) where the method cannot do
    /// without it: every run of FORM and SORM, and those of sampling methods under
    /// [`OnFailure::Error`](super::OnFailure::Error).
    #[error("run {run} failed at u = {u:?}{}: {message}", physical_text(.x))]
    RunFailed {
        /// The run index.
        run: u64,
        /// The point in standard normal space.
        u: Vec<f64>,
        /// The physical inputs there, when the model knows them.
        x: Option<Vec<f64>>,
        /// What the model reported.
        message: String,
    },
    /// The gradient of the limit state is zero (or not finite) at a point: no search
    /// direction (e.g. the origin of `g = c - |u|^2`, or a model that does not depend on
    /// its inputs there).
    #[error(
        "the gradient of the limit state is zero or not finite at u = {u:?} \
         (|grad g| = {norm}); FORM has no search direction there"
    )]
    ZeroGradient {
        /// The point.
        u: Vec<f64>,
        /// The norm of the finite-difference gradient.
        norm: f64,
    },
    /// The model returned a number of outcomes different from the number of points.
    #[error("the model returned {got} outcomes for a batch of {expected} points")]
    BatchSize {
        /// Points in the batch.
        expected: usize,
        /// Outcomes returned.
        got: usize,
    },
    /// The evaluation was stopped by the caller, or a replay did not match.
    #[error(transparent)]
    Aborted(#[from] Abort),
}

fn physical_text(x: &Option<Vec<f64>>) -> String {
    match x {
        Some(x) => format!(" (x = {x:?})"),
        None => String::new(),
    }
}
