//! Results of a two-level (nested) study: the variance split and the intervals of each scalar
//! quantity (in `summary.json` under `quantities.NAME`), the conditional statistics per outer
//! sample (`<q>_conditional.csv`) and the split of each output over time (`<V>_split.csv`).

use serde::Serialize;

/// `quantities.NAME.variance_split`: `Var = E_outer[Var_inner] + Var_outer[E_inner]` as
/// fractions, with their intervals and the variances themselves.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct VarianceSplit {
    /// Fraction of the variance from the inner parameters, `E_outer[Var_inner] / Var`.
    pub inner: f64,
    /// Fraction from the outer parameters, `Var_outer[E_inner] / Var` (0 when the corrected
    /// estimate is negative).
    pub outer: f64,
    /// Confidence interval of `inner`.
    pub inner_ci: [f64; 2],
    /// Confidence interval of `outer`.
    pub outer_ci: [f64; 2],
    /// `E_outer[Var_inner]`.
    pub var_inner: f64,
    /// `Var_outer[E_inner]`, corrected for the inner sampling error (may be negative).
    pub var_outer: f64,
    /// The plug-in sample variance of the conditional means, before the correction.
    pub var_outer_plugin: f64,
    /// The correction: the mean squared standard error of the conditional means (0 for a
    /// collocation or chaos inner method).
    pub correction: f64,
}

/// P(q > limit) over both levels: the mean of the conditional probabilities, its interval, and
/// how the conditional probability spreads over the outer samples.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct ExceedanceInterval {
    /// The limit.
    pub limit: f64,
    /// Marginal probability: the mean over the outer samples of P(q > limit | outer).
    pub p: f64,
    /// Its 95 % interval.
    pub ci: [f64; 2],
    /// How `ci` was found: `outer_bootstrap` (percentile bootstrap over the outer samples),
    /// `outer_student_t` (Student's t on the mean of the conditional probabilities, where it
    /// is wider than the bootstrap: few outer samples; clipped to [0, 1]) or
    /// `outer_one_sided` (every conditional probability 0, or every one 1: the one-sided
    /// 95 % bound `1 − 0.05^(1/N)`, or `0.05^(1/N)`, over the `N` outer samples).
    pub ci_kind: &'static str,
    /// Smallest conditional probability over the outer samples.
    pub conditional_min: f64,
    /// Median of the conditional probabilities.
    pub conditional_median: f64,
    /// Largest conditional probability.
    pub conditional_max: f64,
}

/// What a nested study adds to a scalar quantity's statistics.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct NestedScalar {
    /// The variance split.
    pub variance_split: VarianceSplit,
    /// Confidence interval of the marginal mean.
    pub mean_ci: [f64; 2],
    /// How `mean_ci` was found: `outer_bootstrap`, or `outer_student_t` where Student's t
    /// on the conditional means is wider (few outer samples).
    pub mean_ci_kind: &'static str,
    /// Confidence interval of the marginal Std.
    pub std_ci: [f64; 2],
    /// Marginal exceedance probabilities with intervals, one per limit.
    pub exceedance_ci: Vec<ExceedanceInterval>,
    /// How the intervals are computed.
    pub intervals: String,
    /// Outer samples with a conditional estimate.
    pub outer_samples: usize,
    /// The file with the conditional statistics per outer sample.
    pub conditional_csv: String,
    /// The conditional statistics (for the report).
    #[serde(skip)]
    pub conditional: ConditionalTable,
}

/// The conditional statistics of a quantity, one row per outer sample with an estimate.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct ConditionalTable {
    /// Names of the outer parameters.
    pub outer_names: Vec<String>,
    /// Names of the inner parameters.
    pub inner_names: Vec<String>,
    /// Index of the outer sample in the outer design.
    pub outer_index: Vec<usize>,
    /// Outer parameter values per row.
    pub outer_values: Vec<Vec<f64>>,
    /// Successful inner runs per row.
    pub runs: Vec<usize>,
    /// Conditional mean.
    pub mean: Vec<f64>,
    /// Conditional Std.
    pub std: Vec<f64>,
    /// Std of the conditional chaos (collocation: beside the quadrature Std).
    pub std_chaos: Option<Vec<f64>>,
    /// Standard error of the conditional mean (sampled inner designs).
    pub std_error_mean: Option<Vec<f64>>,
    /// The limits of the exceedance probabilities.
    pub limits: Vec<f64>,
    /// `exceedance[l][row]`: P(q > `limits[l]` | outer).
    pub exceedance: Vec<Vec<f64>>,
    /// First-order Sobol' indices of the inner parameters per row, if the inner method has them.
    pub sobol_first: Option<Vec<Vec<f64>>>,
    /// The conditional chaos: its multi-indices and the coefficients of each row.
    pub chaos: Option<ConditionalChaos>,
    /// The inner chaos's own truncation-error estimate per row, with its name (`loo`,
    /// `order_difference`, `level_difference`), where the inner method has one.
    pub chaos_error: Option<(String, Vec<f64>)>,
}

/// The conditional chaos of a quantity: the union of the multi-indices of every outer
/// sample's basis (a sparse inner chaos keeps a different basis per outer sample), in graded
/// order (total degree, then as the chaos's total-degree set lists
/// them), and per outer sample the coefficient of each (0 for a term its basis does not
/// keep).
pub type ConditionalChaos = (Vec<Vec<usize>>, Vec<Vec<f64>>);

/// The split of an output over time.
#[derive(Clone, Debug, PartialEq)]
pub struct OutputSplit {
    /// Output name.
    pub name: String,
    /// Communication points (s).
    pub times: Vec<f64>,
    /// Marginal mean.
    pub mean: Vec<f64>,
    /// Marginal Std.
    pub std: Vec<f64>,
    /// `E_outer[Var_inner]` over time.
    pub var_inner: Vec<f64>,
    /// Corrected `Var_outer[E_inner]` over time (may be negative).
    pub var_outer: Vec<f64>,
    /// Outer samples with a conditional estimate.
    pub outer_samples: usize,
}
