//! The adaptive evaluation path: methods that ask for batches of points as they go (the
//! reliability methods `form`, `sorm`, `importance_sampling`, `subset`) or run one fixed
//! batch whose points are not samples of the inputs' law (`morris`).
//!
//! # The model
//!
//! The study hands the method a [`BatchModel`]: it evaluates a batch of points of the
//! independent standard normal space `u` (`d` coordinates; the physical inputs are
//! `x = T(u)` by [`RandomInputs::to_physical`] with [`Germ::Normal`], every input family and
//! the Gaussian copula of correlated inputs), in parallel, and returns the value of every
//! scalar quantity of the study at each point (or why the run failed). Points carry a run
//! index (`0, 1, 2, ...` in the order of the requests, over the whole study), so that a study
//! stores each run under its index and, after a kill, answers the stored runs from the store:
//! the methods are deterministic functions of the settings, the seed and the values returned,
//! so the resumed study asks for the same points and gives the same numbers (see
//! `crate::uq::reliability`).
//!
//! # Targets
//!
//! A *target* is one quantity against one limit, on one side: `P(q > limit)` (the `limits`
//! of a `[[qoi]]`) or `P(q < limit)` (its `limits_below`). A reliability method analyses each
//! target in turn, on runs of its own (FORM finds one design point per limit), numbered on
//! from the last run of the target before. Its limit state is `g = limit − q` (above) or
//! `g = q − limit` (below), failure `g ≤ 0`.

use serde::{Deserialize, Serialize};

use super::error::{InvalidSettings, MethodError};
use crate::uq::distributions::Germ;
use crate::uq::random_inputs::RandomInputs;
use crate::uq::reliability::{
    Abort, FormResult, ImportanceSamplingResult, LimitState, MorrisResult, MultiStartResult,
    OnFailure, Outcome, Point, ReliabilityError, Side, SormResult, SubsetResult, Threshold,
};
use crate::uq::special::norm_isf;

/// What a failed run (or a value that is not finite) counts as in a sampling method
/// (`importance_sampling`, `subset`). FORM and SORM need every run.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum FailedRuns {
    /// The study stops with an error naming the run (dropping it would bias the estimate).
    #[default]
    Error,
    /// The run counts as a failure of the system (`g = −∞`): e.g. a simulation that breaks
    /// down because the vehicle derails.
    CountAsFailure,
}

impl FailedRuns {
    pub(crate) fn policy(self) -> OnFailure {
        match self {
            FailedRuns::Error => OnFailure::Error,
            FailedRuns::CountAsFailure => OnFailure::CountAsFailure,
        }
    }
}

/// The model as an adaptive method sees it: every scalar quantity of the study at each point
/// of a batch of the independent standard normal space.
pub(crate) trait BatchModel {
    /// Number of coordinates (random inputs).
    fn dim(&self) -> usize;

    /// One entry per point, in order: the value of every scalar quantity (record order),
    /// or why it is missing (the run failed: every quantity is `Err`). The batch may be run
    /// in parallel; the values must not depend on how. [`Abort`] stops the method (a
    /// `--max-points` budget, a fatal FMU error, a replay that does not match).
    fn evaluate(&mut self, batch: &[Point]) -> Result<Vec<Vec<Outcome>>, Abort>;
}

/// One probability to estimate: scalar quantity `quantity` (its index in record order)
/// against a threshold.
#[derive(Clone, Debug, PartialEq)]
pub(crate) struct Target {
    /// Index of the quantity among the study's scalar quantities.
    pub quantity: usize,
    /// Its name.
    pub name: String,
    /// The limit and the side that fails.
    pub threshold: Threshold,
}

impl Target {
    /// `P(v_hunt < 60)`.
    pub(crate) fn label(&self) -> String {
        let op = match self.threshold.side {
            Side::Above => ">",
            Side::Below => "<",
        };
        format!("P({} {op} {})", self.name, self.threshold.limit)
    }
}

/// The limit state of one target: the target's quantity from the model, through its
/// threshold.
pub(crate) struct TargetLimitState<'m> {
    model: &'m mut dyn BatchModel,
    inputs: &'m RandomInputs,
    target: &'m Target,
}

impl<'m> TargetLimitState<'m> {
    pub(crate) fn new(
        model: &'m mut dyn BatchModel,
        inputs: &'m RandomInputs,
        target: &'m Target,
    ) -> Self {
        TargetLimitState {
            model,
            inputs,
            target,
        }
    }
}

impl LimitState for TargetLimitState<'_> {
    fn dim(&self) -> usize {
        self.model.dim()
    }

    fn evaluate(&mut self, batch: &[Point]) -> Result<Vec<Outcome>, Abort> {
        let values = self.model.evaluate(batch)?;
        let (k, threshold) = (self.target.quantity, self.target.threshold);
        Ok(values
            .into_iter()
            .map(|v| match v.get(k) {
                Some(Ok(q)) => Ok(threshold.g(*q)),
                Some(Err(m)) => Err(m.clone()),
                None => Err(format!("the run gave no value of quantity {k}")),
            })
            .collect())
    }

    fn physical(&self, u: &[f64]) -> Option<Vec<f64>> {
        Some(self.inputs.to_physical(Germ::Normal, u))
    }
}

/// What a reliability method found for one target.
#[derive(Clone, Debug, PartialEq)]
pub(crate) struct LimitResult {
    /// The target.
    pub target: Target,
    /// The method that gave `probability` (`form`, `sorm`, `importance_sampling`,
    /// `subset`).
    pub method: &'static str,
    /// The estimate of the failure probability.
    pub probability: f64,
    /// Its 95 % interval, where the method gives one.
    pub ci_95: Option<[f64; 2]>,
    /// Its coefficient of variation, where the method gives one.
    pub cov: Option<f64>,
    /// A 95 % upper bound when no run failed (subset simulation).
    pub upper_95: Option<f64>,
    /// FORM's reliability index (`form`, `sorm`, `importance_sampling`: that of its FORM),
    /// or the generalised index `−Φ⁻¹(P)` (`subset`).
    pub beta: Option<f64>,
    /// The design point in standard normal space and in physical units.
    pub design_point: Option<(Vec<f64>, Vec<f64>)>,
    /// FORM's importance factors `α_i²` (sum 1).
    pub importance: Option<Vec<f64>>,
    /// The inputs' importance `γ_i²` at FORM's design point (sum 1; equal to `importance`
    /// for independent inputs; [`RandomInputs::importance`]).
    pub importance_gamma: Option<Vec<f64>>,
    /// The first run of this target and how many it made.
    pub first_run: u64,
    /// Runs of this target.
    pub runs: u64,
    /// The FORM search, where one ran.
    pub form: Option<FormResult>,
    /// The multi-start search, where one ran.
    pub multistart: Option<MultiStartResult>,
    /// SORM, where it ran.
    pub sorm: Option<SormResult>,
    /// Importance sampling, where it ran.
    pub importance_sampling: Option<ImportanceSamplingResult>,
    /// Subset simulation, where it ran.
    pub subset: Option<SubsetResult>,
    /// Whether FORM's check at the mirrored design point suspects a second design point.
    pub second_design_point_suspected: bool,
    /// For the user (each already prefixed with the target).
    pub warnings: Vec<String>,
}

impl LimitResult {
    /// An empty result for `target` from `first_run`, filled in by the method.
    pub(crate) fn new(target: &Target, method: &'static str, first_run: u64) -> LimitResult {
        LimitResult {
            target: target.clone(),
            method,
            probability: f64::NAN,
            ci_95: None,
            cov: None,
            upper_95: None,
            beta: None,
            design_point: None,
            importance: None,
            importance_gamma: None,
            first_run,
            runs: 0,
            form: None,
            multistart: None,
            sorm: None,
            importance_sampling: None,
            subset: None,
            second_design_point_suspected: false,
            warnings: Vec::new(),
        }
    }

    /// The FORM analysis this result holds (SORM and importance sampling build on it), or
    /// an error when there is none.
    pub(crate) fn form_analysis(&self) -> Result<&FormResult, ReliabilityError> {
        self.form
            .as_ref()
            .ok_or_else(|| ReliabilityError::Invalid("FORM gave no design point".into()))
    }

    /// Takes FORM's design point, importance factors and index; `inputs` give the importance
    /// of the inputs under their correlation.
    pub(crate) fn with_form(&mut self, f: &FormResult, inputs: &RandomInputs) {
        self.beta = Some(f.beta);
        self.design_point = f.x_star.clone().map(|x| (f.u_star.clone(), x));
        self.importance = Some(f.importance.clone());
        self.importance_gamma = Some(inputs.importance(&f.alpha));
    }

    /// The run index after this target's last run.
    pub(crate) fn next_run(&self) -> u64 {
        self.first_run + self.runs
    }
}

/// The generalised reliability index `−Φ⁻¹(P)` (Ditlevsen 1979), `None` outside (0, 1).
pub(crate) fn generalised_beta(p: f64) -> Option<f64> {
    (p > 0.0 && p < 1.0).then(|| norm_isf(p))
}

/// What a method that screens the inputs found for one quantity.
#[derive(Clone, Debug, PartialEq)]
pub(crate) struct Screening {
    /// Index of the quantity (record order).
    pub quantity: usize,
    /// Its name.
    pub name: String,
    /// Morris's measures per input.
    pub morris: MorrisResult,
}

/// What an adaptive method found.
#[derive(Clone, Debug, Default, PartialEq)]
pub(crate) struct AdaptiveResult {
    /// One per target (reliability methods).
    pub limits: Vec<LimitResult>,
    /// One per quantity (screening).
    pub screening: Vec<Screening>,
    /// Model runs in all.
    pub runs: u64,
}

/// The targets of `quantities` (names in record order, each with its limits above and
/// below), restricted to `only` when it is not empty: every limit above, then every limit
/// below, quantity by quantity.
pub(crate) fn targets(
    quantities: &[(String, Vec<f64>, Vec<f64>)],
    only: &[String],
) -> Result<Vec<Target>, InvalidSettings> {
    if let Some(bad) = only
        .iter()
        .find(|n| !quantities.iter().any(|(q, _, _)| q == *n))
    {
        let names: Vec<&str> = quantities.iter().map(|(q, _, _)| q.as_str()).collect();
        return Err(InvalidSettings(format!(
            "`quantities` names '{bad}', which is not a scalar quantity of the study ({})",
            names.join(", ")
        )));
    }
    let mut out = Vec::new();
    for (k, (name, above, below)) in quantities.iter().enumerate() {
        if !only.is_empty() && !only.contains(name) {
            continue;
        }
        let sides = above
            .iter()
            .map(|&l| (l, Side::Above))
            .chain(below.iter().map(|&l| (l, Side::Below)));
        for (limit, side) in sides {
            out.push(Target {
                quantity: k,
                name: name.clone(),
                threshold: Threshold { limit, side },
            });
        }
    }
    Ok(out)
}

/// Runs `analyse` on every target in turn, each on the limit state of its target and with
/// its runs numbered on from the previous target's; errors name the target.
pub(crate) fn each_target(
    model: &mut dyn BatchModel,
    inputs: &RandomInputs,
    targets: &[Target],
    mut analyse: impl AnalyseTarget,
) -> Result<AdaptiveResult, MethodError> {
    if targets.is_empty() {
        return Err(MethodError::Invalid(InvalidSettings(
            "no limit to estimate a probability of: give the quantities `limits` (P(q > limit)) \
             or `limits_below` (P(q < limit))"
                .into(),
        )));
    }
    let mut next = 0;
    let mut limits = Vec::with_capacity(targets.len());
    for t in targets {
        let mut g = TargetLimitState::new(model, inputs, t);
        let mut r = analyse(&mut g, t, next).map_err(|e| method_error(e, &t.label(), inputs))?;
        let label = t.label();
        for w in &mut r.warnings {
            *w = format!("{label}: {w}");
        }
        next = r.next_run();
        limits.push(r);
    }
    Ok(AdaptiveResult {
        limits,
        screening: Vec::new(),
        runs: next,
    })
}

/// The analysis of one target that [`each_target`] runs: on the target's limit state, for
/// the target, with its runs numbered from the given one.
pub(crate) trait AnalyseTarget:
    FnMut(&mut dyn LimitState, &Target, u64) -> Result<LimitResult, ReliabilityError>
{
}

impl<F> AnalyseTarget for F where
    F: FnMut(&mut dyn LimitState, &Target, u64) -> Result<LimitResult, ReliabilityError>
{
}

/// A reliability method that analyses each target on its own (FORM, SORM, importance
/// sampling, subset simulation): its [`Adaptive::run`](super::traits::Adaptive::run) is
/// [`each_target`] over its analysis ([`per_target_items`]).
pub(crate) trait PerTarget {
    /// The analysis of a target on `inputs`, deterministic in `seed`; what holds for every
    /// target (the settings, a given point) is worked out once, here.
    fn analyser(&self, inputs: &RandomInputs, seed: u64)
        -> Result<impl AnalyseTarget, MethodError>;
}

/// The [`Adaptive::only`](super::traits::Adaptive::only) (the method's `quantities`) and
/// [`Adaptive::run`](super::traits::Adaptive::run) ([`each_target`] over
/// [`PerTarget::analyser`]) of a [`PerTarget`] method. Used inside `impl Adaptive for …`.
macro_rules! per_target_items {
    () => {
        fn only(&self) -> &[String] {
            &self.quantities
        }

        fn run(
            &self,
            model: &mut dyn $crate::uq::method::adaptive::BatchModel,
            inputs: &$crate::uq::random_inputs::RandomInputs,
            targets: &[$crate::uq::method::adaptive::Target],
            _names: &[String],
            seed: u64,
        ) -> Result<$crate::uq::method::adaptive::AdaptiveResult, $crate::uq::method::MethodError> {
            let analyse = $crate::uq::method::adaptive::PerTarget::analyser(self, inputs, seed)?;
            $crate::uq::method::adaptive::each_target(model, inputs, targets, analyse)
        }
    };
}
pub(crate) use per_target_items;

/// A reliability error as a method error, naming `target` and the physical inputs.
pub(crate) fn method_error(
    e: ReliabilityError,
    target: &str,
    inputs: &RandomInputs,
) -> MethodError {
    let named = |u: &[f64]| -> Vec<(String, f64)> {
        inputs
            .iter()
            .map(|p| p.name.clone())
            .zip(inputs.to_physical(Germ::Normal, u))
            .collect()
    };
    let target = target.to_owned();
    match e {
        ReliabilityError::Invalid(m) => MethodError::Invalid(InvalidSettings(m)),
        ReliabilityError::NoInputs => {
            MethodError::Invalid(InvalidSettings("the study has no random input".into()))
        }
        ReliabilityError::RunFailed {
            run, u, message, ..
        } => MethodError::RunFailed {
            target,
            run,
            values: named(&u),
            message,
        },
        ReliabilityError::ZeroGradient { u, norm } => MethodError::NoSearchDirection {
            target,
            values: named(&u),
            norm,
        },
        ReliabilityError::BatchSize { expected, got } => MethodError::ResultsMismatch(format!(
            "the model returned {got} outcomes for a batch of {expected} points"
        )),
        ReliabilityError::Aborted(Abort::Interrupted(why)) => MethodError::Stopped { target, why },
        ReliabilityError::Aborted(a @ Abort::ReplayMismatch { .. }) => MethodError::Stopped {
            target,
            why: a.to_string(),
        },
    }
}

/// The standard normal point of physical values given by name (`centre` of importance
/// sampling, `start` of FORM): every random parameter, finite, inside its support.
pub(crate) fn standard_point(
    inputs: &RandomInputs,
    values: &std::collections::BTreeMap<String, f64>,
    what: &str,
) -> Result<Vec<f64>, InvalidSettings> {
    if let Some(bad) = values
        .keys()
        .find(|k| !inputs.iter().any(|p| &p.name == *k))
    {
        return Err(InvalidSettings(format!(
            "{what} names '{bad}', which is not a random parameter"
        )));
    }
    let mut x = Vec::with_capacity(inputs.len());
    for p in inputs.iter() {
        let Some(&v) = values.get(&p.name) else {
            return Err(InvalidSettings(format!(
                "{what} gives no value of the random parameter '{}' (every one is needed)",
                p.name
            )));
        };
        let (lo, hi) = p.distribution.support();
        if !(v.is_finite() && v > lo && v < hi) {
            return Err(InvalidSettings(format!(
                "{what}: {} = {v} is not inside the support ({lo}, {hi}) of its distribution",
                p.name
            )));
        }
        x.push(v);
    }
    Ok(inputs.to_germ(Germ::Normal, &x))
}

/// Checks that every input suits a method that differentiates the limit state (FORM,
/// SORM): a discrete input makes `g` a staircase in its coordinate.
pub(crate) fn check_continuous(
    parameters: &[crate::uq::distributions::RandomParameter],
    kind: &str,
) -> Result<(), InvalidSettings> {
    match parameters.iter().find(|p| p.distribution.is_discrete()) {
        Some(p) => Err(InvalidSettings(format!(
            "'{}' is a discrete (integer_uniform) input: {kind} differentiates the limit state, \
             which is a staircase in a discrete input (use `subset` or a sampling method)",
            p.name
        ))),
        None => Ok(()),
    }
}

#[cfg(test)]
pub(crate) mod tests {
    //! An analytic batch model shared by the method modules' tests.

    use super::*;
    use crate::uq::distributions::{Distribution, RandomParameter};

    /// A model of the physical inputs with one or more closed-form quantities, counting
    /// its runs and checking that they arrive numbered in order.
    pub(crate) struct Analytic<'a, F> {
        pub inputs: &'a RandomInputs,
        pub f: F,
        pub runs: u64,
        pub batches: usize,
    }

    impl<'a, F: Fn(&[f64]) -> Vec<Outcome>> Analytic<'a, F> {
        pub(crate) fn new(inputs: &'a RandomInputs, f: F) -> Self {
            Analytic {
                inputs,
                f,
                runs: 0,
                batches: 0,
            }
        }
    }

    impl<F: Fn(&[f64]) -> Vec<Outcome>> BatchModel for Analytic<'_, F> {
        fn dim(&self) -> usize {
            self.inputs.len()
        }

        fn evaluate(&mut self, batch: &[Point]) -> Result<Vec<Vec<Outcome>>, Abort> {
            self.batches += 1;
            Ok(batch
                .iter()
                .map(|p| {
                    assert_eq!(p.run, self.runs, "runs are numbered in order");
                    self.runs += 1;
                    (self.f)(&self.inputs.to_physical(Germ::Normal, &p.u))
                })
                .collect())
        }
    }

    /// The one target `P(name > limit)`.
    pub(crate) fn above(name: &str, limit: f64) -> Vec<Target> {
        targets(&[(name.to_string(), vec![limit], vec![])], &[]).unwrap()
    }

    /// `d` standard normal inputs named `x1..xd`.
    pub(crate) fn standard_inputs(d: usize) -> RandomInputs {
        RandomInputs::independent(
            (1..=d)
                .map(|i| {
                    RandomParameter::new(format!("x{i}"), Distribution::normal(0.0, 1.0).unwrap())
                })
                .collect(),
        )
    }

    #[test]
    fn targets_list_every_limit_above_then_below_and_refuse_an_unknown_name() {
        let q = vec![
            ("a".to_string(), vec![1.0, 2.0], vec![-1.0]),
            ("b".to_string(), vec![], vec![0.5]),
        ];
        let t = targets(&q, &[]).unwrap();
        let labels: Vec<String> = t.iter().map(Target::label).collect();
        assert_eq!(labels, ["P(a > 1)", "P(a > 2)", "P(a < -1)", "P(b < 0.5)"]);
        assert_eq!(t[3].quantity, 1);
        let only = targets(&q, &["b".to_string()]).unwrap();
        assert_eq!(only.len(), 1);
        let e = targets(&q, &["c".to_string()]).unwrap_err();
        assert!(e.0.contains("'c'") && e.0.contains("a, b"), "{e}");
    }

    #[test]
    fn a_standard_point_maps_physical_values_back_and_refuses_gaps() {
        let inputs = RandomInputs::independent(vec![
            RandomParameter::new("k", Distribution::normal(10.0, 2.0).unwrap()),
            RandomParameter::new("c", Distribution::lognormal(0.0, 0.5).unwrap()),
        ]);
        let values = [("k".to_string(), 14.0), ("c".to_string(), 1.0)]
            .into_iter()
            .collect();
        let u = standard_point(&inputs, &values, "centre").unwrap();
        assert!((u[0] - 2.0).abs() < 1e-12 && u[1].abs() < 1e-12, "{u:?}");
        let partial = [("k".to_string(), 14.0)].into_iter().collect();
        assert!(standard_point(&inputs, &partial, "centre").is_err());
        let outside = [("k".to_string(), 14.0), ("c".to_string(), -1.0)]
            .into_iter()
            .collect();
        let e = standard_point(&inputs, &outside, "centre").unwrap_err();
        assert!(e.0.contains("support"), "{e}");
    }
}
