//! Small probabilities and screening in `summary.json`: `quantities.NAME.reliability` (one
//! entry per limit, every method that gives probabilities) and `quantities.NAME.morris`.

use std::collections::BTreeMap;

use serde::Serialize;

use crate::results::by_name;
use crate::uq::method::adaptive::{generalised_beta, LimitResult, Screening};
use crate::uq::reliability::Side;

/// One probability of a quantity against a limit (`quantities.NAME.reliability[k]` in
/// `summary.json`). Fields a method does not give are `null`.
#[derive(Clone, Debug, PartialEq, Serialize)]
#[non_exhaustive]
pub struct LimitProbability {
    /// The limit, in the quantity's unit.
    pub limit: f64,
    /// `above` (`P(q > limit)`, the quantity's `limits`) or `below` (`P(q < limit)`, its
    /// `limits_below`).
    pub direction: &'static str,
    /// The estimate of the probability.
    pub p: f64,
    /// Its 95 % interval (`null` where the method gives none, e.g. FORM and SORM, which have
    /// no error estimate).
    pub ci_95: Option<[f64; 2]>,
    /// Its coefficient of variation (sampling methods).
    pub cov: Option<f64>,
    /// Reliability index: FORM's `β` (`form`, `sorm`, and `importance_sampling` after
    /// FORM), else the generalised index `−Φ⁻¹(p)`.
    pub beta: Option<f64>,
    /// FORM's design point in physical units, by parameter name.
    pub design_point: Option<BTreeMap<String, f64>>,
    /// FORM's importance factors `α_i²` by parameter name (sum 1; with correlated inputs
    /// those of the independent coordinates in the order of `[[parameters]]`).
    pub importance: Option<BTreeMap<String, f64>>,
    /// The importance of each input at FORM's design point, `γ_i²` by parameter name (sum 1):
    /// `γ = L⁻ᵀα / |L⁻ᵀα|` with `L` the Cholesky factor of the inputs' normal-space
    /// correlation (Der Kiureghian's importance vector). Equal to `importance` for
    /// independent inputs; with correlated ones it ranks the inputs themselves (for a linear
    /// quantity of normal inputs `γ_i ∝ c_i σ_i`, whatever the correlation).
    pub importance_gamma: Option<BTreeMap<String, f64>>,
    /// Model runs this probability took (or the runs / draws counted, for a sampling
    /// method).
    pub runs: usize,
    /// The method that gave `p`: `form`, `sorm`, `importance_sampling`, `subset`, or the
    /// sampling method's kind (counted over its runs), or `chaos` (counted over draws of a
    /// chaos surrogate).
    pub method: String,
    /// A one-sided 95 % upper bound of `p` when no run (or draw) failed; `null` otherwise.
    pub upper_95: Option<f64>,
    /// How `ci_95` was found, in words.
    pub ci_kind: Option<String>,
    /// What the method reported besides (the FORM iterations, the SORM curvatures, the
    /// importance-sampling and subset histories, the multi-start design points), under
    /// the keys `form`, `sorm`, `importance_sampling`, `subset`, `multistart`.
    #[serde(flatten)]
    pub details: serde_json::Map<String, serde_json::Value>,
    /// Warnings of this probability.
    pub warnings: Vec<String>,
    /// The method's own result (the report's plots).
    #[serde(skip)]
    pub(crate) result: Option<Box<LimitResult>>,
    /// Counted over draws of a chaos beyond (or nearly beyond) its model runs: the chaos's
    /// extrapolation, given no interval (the analysis then looks for the chaos's own design
    /// point).
    #[serde(skip)]
    pub(crate) tail_extrapolated: bool,
}

/// The JSON of a method's details, if it ran (and they serialize).
fn json<T: Serialize>(details: &Option<T>) -> Option<serde_json::Value> {
    details.as_ref().and_then(|d| serde_json::to_value(d).ok())
}

/// `above` or `below`.
pub(crate) fn direction(side: Side) -> &'static str {
    match side {
        Side::Above => "above",
        Side::Below => "below",
    }
}

impl LimitProbability {
    /// The coefficient of variation in words (`CoV 4.9 %`); for subset simulation, whose
    /// `cov` takes the levels as independent (the usual figure, found 1.2 to 1.4 times too
    /// small), with the fully correlated value its interval is built on beside it.
    pub(crate) fn cov_words(&self) -> Option<String> {
        let c = self.cov?;
        let upper = self
            .details
            .get("subset")
            .and_then(|s| s.get("cov_upper"))
            .and_then(serde_json::Value::as_f64);
        Some(match upper {
            Some(u) => format!(
                "CoV {:.1} % with independent levels, {:.1} % with correlated ones (which \
                 the interval uses)",
                100.0 * c,
                100.0 * u
            ),
            None => format!("CoV {:.1} %", 100.0 * c),
        })
    }

    /// The entry of an adaptive method's result, the parameters named by `names`.
    pub(crate) fn of(r: &LimitResult, names: &[&str]) -> LimitProbability {
        let label = |v: &[f64]| by_name(names, v.iter().copied());
        let mut details = serde_json::Map::new();
        let mut put = |key: &str, v: Option<serde_json::Value>| {
            if let Some(v) = v {
                details.insert(key.to_owned(), v);
            }
        };
        put("form", json(&r.form));
        put("sorm", json(&r.sorm));
        put("importance_sampling", json(&r.importance_sampling));
        put("subset", json(&r.subset));
        put("multistart", json(&r.multistart));
        let ci_kind = r.ci_95.map(|_| match r.method {
            "subset" => "log-normal on the CoV of fully correlated levels (conservative)".into(),
            _ => "log-normal with the estimated CoV".into(),
        });
        LimitProbability {
            limit: r.target.threshold.limit,
            direction: direction(r.target.threshold.side),
            p: r.probability,
            ci_95: r.ci_95,
            cov: r.cov,
            beta: r.beta,
            design_point: r.design_point.as_ref().map(|(_, x)| label(x)),
            importance: r.importance.as_deref().map(label),
            importance_gamma: r.importance_gamma.as_deref().map(label),
            runs: r.runs as usize,
            method: r.method.to_owned(),
            upper_95: r.upper_95,
            ci_kind,
            details,
            warnings: r.warnings.clone(),
            result: Some(Box::new(r.clone())),
            tail_extrapolated: false,
        }
    }

    /// The entry of a probability counted over `of` runs or draws (`k` of them on the failing
    /// side), with its interval `ci_95` (of kind `ci_kind`) and upper bound.
    #[allow(clippy::too_many_arguments)]
    pub(crate) fn counted(
        limit: f64,
        side: Side,
        k: usize,
        of: usize,
        ci_95: Option<[f64; 2]>,
        upper_95: f64,
        method: &str,
        ci_kind: &str,
    ) -> LimitProbability {
        let p = if of == 0 {
            f64::NAN
        } else {
            k as f64 / of as f64
        };
        LimitProbability {
            limit,
            direction: direction(side),
            p,
            ci_95,
            cov: (k > 0).then(|| ((1.0 - p) / (of as f64 * p)).sqrt()),
            beta: generalised_beta(p),
            design_point: None,
            importance: None,
            importance_gamma: None,
            runs: of,
            method: method.to_owned(),
            upper_95: (k == 0).then_some(upper_95),
            ci_kind: ci_95.map(|_| ci_kind.to_owned()),
            details: serde_json::Map::new(),
            warnings: Vec::new(),
            result: None,
            tail_extrapolated: false,
        }
    }

    /// `P(v_hunt < 60)`.
    pub fn label(&self, quantity: &str) -> String {
        let op = if self.direction == "below" { "<" } else { ">" };
        format!("P({quantity} {op} {})", self.limit)
    }
}

/// Morris's screening measures of a quantity (`quantities.NAME.morris`), by parameter name,
/// per unit of probability level of each input.
#[derive(Clone, Debug, PartialEq, Serialize)]
#[non_exhaustive]
pub struct MorrisScreening {
    /// Mean absolute elementary effect `μ*` (the ranking measure).
    pub mu_star: BTreeMap<String, f64>,
    /// Standard deviation of the elementary effects `σ` (non-linearity, interactions).
    pub sigma: BTreeMap<String, f64>,
    /// Mean elementary effect `μ`.
    pub mu: BTreeMap<String, f64>,
    /// The parameters by decreasing `μ*`.
    pub ranking: Vec<String>,
    /// Elementary effects per parameter (fewer than the trajectories where runs failed).
    pub effects: BTreeMap<String, usize>,
    /// Warnings.
    pub warnings: Vec<String>,
}

impl MorrisScreening {
    /// The entry of a screening, the parameters named by `names`.
    pub(crate) fn of(s: &Screening, names: &[&str]) -> MorrisScreening {
        let m = &s.morris;
        let label = |v: &[f64]| by_name(names, v.iter().copied());
        MorrisScreening {
            mu_star: label(&m.mu_star),
            sigma: label(&m.sigma),
            mu: label(&m.mu),
            ranking: m.ranking.iter().map(|&i| names[i].to_owned()).collect(),
            effects: by_name(names, m.effects.iter().copied()),
            warnings: m.warnings.clone(),
        }
    }
}
