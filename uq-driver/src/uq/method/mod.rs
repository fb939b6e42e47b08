//! UQ methods, one module per method. Each owns its design (where the model is run, with
//! which weights) and its estimator (moments, chaos, Sobol' indices from the results).
//!
//! The study runner and the report see a method only through [`Method`]:
//! - a [`Sampling`] method builds a [`Design`] (points in a standard space and their physical
//!   values, optional weights) from the study's random parameters; the runner evaluates the
//!   model at every point; the method's estimator turns a results matrix (points × columns:
//!   the time steps of an output, or one scalar quantity) into an [`Estimate`];
//! - an [`Intrusive`] method solves a projected system itself and returns one [`Estimate`]
//!   per output ([`Solution`]);
//! - an adaptive method ([`Evaluation::Adaptive`]: the reliability methods [`form`],
//!   [`sorm`], [`importance_sampling`], [`subset`], and [`morris`] screening) asks for batches
//!   of points as it goes; the study runs each batch through its runner and stores every run
//!   (see `adaptive`).
//!
//! An [`Estimate`] holds moments per column, optionally a chaos surrogate (evaluable and
//! sampleable), Sobol' indices and standard errors, and says where densities and quantiles
//! are to be drawn from ([`Draws`]).
//!
//! **Adding a method**: write `uq/method/<name>.rs` with a settings struct (serde,
//! `deny_unknown_fields`) that implements [`Method`] and [`Sampling`] or [`Intrusive`], and
//! add one line `<name>::<Type>,` to the `methods!` list below. The study file then accepts
//! `[method] kind = "<type in snake_case>"` with the struct's fields as keys.
//!
//! How the methods to come fit (settings and structure are the method's own; the estimator
//! receives its settings as `&self`, so it can rebuild any structure of its design):
//! - a sparse grid: a [`Design`] with (possibly negative) weights; the estimator combines
//!   full-tensor projections over the grid's index sets into [`Estimate::chaos`];
//! - regression chaos: the design of another sampling method, the chaos fitted to the rows
//!   that succeeded (`rows`), its leave-one-out error as a new field of [`Estimate`];
//! - quasi-Monte Carlo and replicated Latin hypercubes: point `i` belongs to replicate
//!   `i / samples`; the standard error of the mean comes from the replicates;
//! - pick-freeze Sobol' sampling: the blocks A, B and A_B^(j) by point index; [`Sobol`] from
//!   the blocks;
//! - a nested study: the product of an outer and an inner design, and for every outer sample
//!   the inner method's own [`Sampling::estimate`] on that sample's rows.

pub(crate) mod adaptive;
mod chaos;
mod design;
mod error;
mod estimate;
mod sample;
mod traits;

use serde::{Deserialize, Serialize};

pub use adaptive::FailedRuns;
pub use chaos::ChaosBasis;
pub use design::Design;
pub use error::{InvalidSettings, MethodError};
pub use estimate::{ChaosError, ChaosErrorKind, Draws, Estimate, Sobol, SobolIntervals};
pub use traits::{
    details, hyperbolic_terms, AdaptiveMethod, ChaosFit, Evaluation, Intrusive, KindNotes, Method,
    MethodSummary, Problem, RunResults, Sampling, Solution,
};

// The method modules: declared here, not by the macro below, so that rustfmt reaches them.
pub mod form;
pub mod importance_sampling;
pub mod lhs;
pub mod mc;
pub mod morris;
pub mod nested;
pub mod nominal;
pub mod pce_regression;
pub mod qmc;
pub mod scm;
pub mod sgm;
pub mod sobol_sampling;
pub mod sorm;
pub mod sparse_grid;
pub mod subset;

/// Builds the `[method]` table from the list of methods: one line per method, `module::Type`,
/// the module's name being the `kind` of study files.
macro_rules! methods {
    ($($module:ident :: $Type:ident),* $(,)?) => {
        /// The `[method]` table of a study: `kind` names the method (the type's name in
        /// snake_case), the other keys are its settings.
        #[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
        #[serde(tag = "kind", rename_all = "snake_case")]
        pub enum MethodSpec {
            $(
                #[allow(missing_docs)]
                $Type($module::$Type),
            )*
        }

        impl MethodSpec {
            /// The method these settings select.
            pub fn method(&self) -> &dyn Method {
                match self {
                    $(MethodSpec::$Type(m) => m,)*
                }
            }

            /// The method these settings select, to be completed (files, levels).
            pub fn method_mut(&mut self) -> &mut dyn Method {
                match self {
                    $(MethodSpec::$Type(m) => m,)*
                }
            }
        }

        /// What the report and the terminal say of the results of the method `kind` (as a
        /// `summary.json` names it); nothing in particular for a kind this build does not know.
        pub fn notes_of_kind(kind: &str) -> KindNotes {
            match kind {
                $(stringify!($module) => <$module::$Type as Method>::notes(),)*
                _ => KindNotes::default(),
            }
        }
    };
}

methods! {
    mc::Mc,
    lhs::Lhs,
    qmc::Qmc,
    sobol_sampling::SobolSampling,
    scm::Scm,
    sgm::Sgm,
    nominal::Nominal,
    sparse_grid::SparseGrid,
    pce_regression::PceRegression,
    nested::Nested,
    form::Form,
    sorm::Sorm,
    importance_sampling::ImportanceSampling,
    subset::Subset,
    morris::Morris,
}

impl MethodSpec {
    /// Resolves the files a method's settings name (e.g. a points file) against `base`,
    /// the study file's folder, and records what must enter the study's hash.
    pub fn resolve_files(&mut self, base: Option<&std::path::Path>) -> Result<(), InvalidSettings> {
        self.method_mut().resolve_files(base)
    }

    /// The two-level settings of a nested study, whose analysis is its own.
    pub fn nested(&self) -> Option<&nested::Nested> {
        match self {
            MethodSpec::Nested(n) => Some(n),
            _ => None,
        }
    }

    /// Takes the parameters marked `level = "outer"` (names, study order): a nested study
    /// draws them in its outer design; any other method refuses them.
    pub fn set_levels(&mut self, outer: &[String]) -> Result<(), InvalidSettings> {
        self.method_mut().set_outer_parameters(outer)
    }
}

#[cfg(test)]
mod tests {
    use nalgebra::DMatrix;

    use super::*;
    use crate::uq::distributions::RandomParameter;
    use crate::uq::random_inputs::RandomInputs;

    #[test]
    fn kinds_are_the_snake_case_variant_names() {
        let toml_kind = |t: &str| -> MethodSpec { toml::from_str(t).unwrap() };
        for (text, kind) in [
            ("kind = \"mc\"\nsamples = 10", "mc"),
            ("kind = \"lhs\"\nsamples = 10", "lhs"),
            ("kind = \"lhs\"\nsamples = 10\nreplicates = 4", "lhs"),
            ("kind = \"qmc\"\nsamples = 16", "qmc"),
            ("kind = \"sobol_sampling\"\nsamples = 16", "sobol_sampling"),
            ("kind = \"scm\"\nnodes = 3", "scm"),
            ("kind = \"sgm\"\norder = 2", "sgm"),
            ("kind = \"nominal\"", "nominal"),
            ("kind = \"sparse_grid\"\nlevel = 2", "sparse_grid"),
            (
                "kind = \"pce_regression\"\nsamples = 10\norder = 2",
                "pce_regression",
            ),
        ] {
            let m = toml_kind(text);
            assert_eq!(m.method().kind(), kind);
            // The serialized settings are those written (the study hash depends on them).
            let json = serde_json::to_value(&m).unwrap();
            assert_eq!(json["kind"], kind);
        }
    }

    #[test]
    fn settings_of_another_method_are_refused() {
        for text in [
            "kind = \"lhs\"\nnodes = 3\nsamples = 10",
            "kind = \"scm\"\nsamples = 10\nnodes = 3",
            "kind = \"nominal\"\norder = 1",
            "kind = \"mc\"",
            "kind = \"mc\"\nsamples = 10\nreplicates = 4",
            "kind = \"qmc\"\nnodes = 3",
        ] {
            let r: Result<MethodSpec, _> = toml::from_str(text);
            assert!(r.is_err(), "{text}");
        }
    }

    /// The analytic fixture every sampling method is checked against, through the trait
    /// only: f = K + K C + C² with K ~ N(a, s²), C ~ N(b, t²), independent. With K = a + sξ,
    /// C = b + tη: mean a + ab + b² + t², variance s²(1+b)² + t²(a+2b)² + s²t² + 2t⁴.
    #[test]
    fn every_sampling_method_estimates_the_analytic_fixture() {
        let (a, s_k, b, t) = (2.0, 0.5, 1.0, 0.2);
        let params = RandomInputs::independent(vec![
            RandomParameter::new("K", crate::uq::Distribution::normal(a, s_k).unwrap()),
            RandomParameter::new("C", crate::uq::Distribution::normal(b, t).unwrap()),
        ]);
        let f = |v: &[f64]| v[0] + v[0] * v[1] + v[1] * v[1];
        let mean = a + a * b + b * b + t * t;
        let parts = [
            s_k * s_k * (1.0 + b) * (1.0 + b),
            t * t * (a + 2.0 * b) * (a + 2.0 * b) + 2.0 * t.powi(4),
            s_k * s_k * t * t,
        ];
        let var: f64 = parts.iter().sum();
        for text in [
            "kind = \"mc\"\nsamples = 20000",
            "kind = \"lhs\"\nsamples = 20000",
            "kind = \"lhs\"\nsamples = 2000\nreplicates = 10",
            "kind = \"qmc\"\nsamples = 4096\nreplicates = 8",
            "kind = \"sobol_sampling\"\nsamples = 8192",
            "kind = \"scm\"\nnodes = 3",
            "kind = \"nominal\"",
            "kind = \"sparse_grid\"\nlevel = 2",
            "kind = \"pce_regression\"\nsamples = 20\norder = 2",
            "kind = \"pce_regression\"\nsamples = 20\norder = 4\nsparse = true\ndesign = \"qmc\"",
        ] {
            let spec: MethodSpec = toml::from_str(text).unwrap();
            let m = sampling(&spec);
            let design = m.design(&params, 7).unwrap();
            let values: Vec<f64> = design.values.iter().map(|v| f(v)).collect();
            let data = DMatrix::from_column_slice(values.len(), 1, &values);
            let rows: Vec<usize> = (0..design.len()).collect();
            let e = m.estimate(&design, &rows, &data).unwrap();
            match spec.method().kind() {
                "nominal" => {
                    assert_eq!(e.mean[0], f(&[a, b]));
                    assert_eq!(e.std[0], 0.0);
                }
                "scm" => {
                    // Degree 4 in each germ: the 3-node rule is exact, and so is the order-2 chaos.
                    assert!((e.mean[0] - mean).abs() < 1e-12, "{}", e.mean[0]);
                    assert!((e.std[0] - var.sqrt()).abs() < 1e-12, "{}", e.std[0]);
                    assert!((e.std_chaos.as_ref().unwrap()[0] - var.sqrt()).abs() < 1e-12);
                    let sobol = e.sobol.unwrap();
                    assert!((sobol.first[0][0] - parts[0] / var).abs() < 1e-12);
                    assert!((sobol.first[0][1] - parts[1] / var).abs() < 1e-12);
                    assert!((sobol.total[0][0] - (parts[0] + parts[2]) / var).abs() < 1e-12);
                    assert_eq!(e.draws, Draws::Chaos);
                }
                "sobol_sampling" => {
                    // Pick-freeze indices of the same fixture, within sampling error.
                    let sobol = e.sobol.unwrap();
                    assert!((sobol.first[0][0] - parts[0] / var).abs() < 0.03);
                    assert!((sobol.first[0][1] - parts[1] / var).abs() < 0.03);
                    assert!((sobol.total[0][0] - (parts[0] + parts[2]) / var).abs() < 0.03);
                    assert!(sobol.intervals.is_some());
                    assert!((e.mean[0] - mean).abs() < 4.0 * e.std_error_mean.unwrap()[0]);
                    assert!((e.std[0] / var.sqrt() - 1.0).abs() < 0.03);
                }
                kind @ ("sparse_grid" | "pce_regression") => {
                    // A polynomial of degree 2 in the chaos space: exact, with a vanishing
                    // error estimate.
                    assert!((e.mean[0] - mean).abs() < 1e-11, "{text}: {}", e.mean[0]);
                    assert!(
                        (e.std[0] - var.sqrt()).abs() < 1e-11,
                        "{text}: {}",
                        e.std[0]
                    );
                    let sobol = e.sobol.unwrap();
                    assert!((sobol.first[0][1] - parts[1] / var).abs() < 1e-11);
                    assert!((sobol.total[0][0] - (parts[0] + parts[2]) / var).abs() < 1e-11);
                    let err = e.chaos_error.unwrap().values[0];
                    if kind == "sparse_grid" {
                        // Level 1 misses exactly the K C interaction: its variance share.
                        assert!((err - parts[2] / var).abs() < 1e-12, "{err}");
                    } else {
                        assert!(err < 1e-20, "{text}: {err}");
                    }
                    assert_eq!(e.draws, Draws::Chaos);
                }
                kind => {
                    let se = e.std_error_mean.as_ref().unwrap()[0];
                    if !text.contains("replicates") {
                        assert!((se - e.std[0] / 20000f64.sqrt()).abs() < 1e-15);
                    }
                    assert!((e.mean[0] - mean).abs() < 4.0 * se, "{kind}: {}", e.mean[0]);
                    assert!(
                        (e.std[0] / var.sqrt() - 1.0).abs() < 0.03,
                        "{kind}: {}",
                        e.std[0]
                    );
                    assert_eq!(e.draws, Draws::Runs);
                }
            }
        }
    }

    #[test]
    fn a_weighted_design_refuses_a_missing_point() {
        let spec: MethodSpec = toml::from_str("kind = \"scm\"\nnodes = 2").unwrap();
        let m = sampling(&spec);
        let params = RandomInputs::independent(vec![RandomParameter::new(
            "K",
            crate::uq::Distribution::normal(1.0, 0.1).unwrap(),
        )]);
        let design = m.design(&params, 0).unwrap();
        let data = DMatrix::from_element(1, 3, 1.0);
        let e = m.estimate(&design, &[1], &data).unwrap_err();
        assert!(matches!(
            e,
            MethodError::MissingPoints {
                missing: 1,
                total: 2
            }
        ));
    }

    fn normal_inputs(dim: usize) -> RandomInputs {
        RandomInputs::independent(
            (0..dim)
                .map(|i| {
                    RandomParameter::new(
                        format!("x{i}"),
                        crate::uq::Distribution::normal(1.0, 0.1).unwrap(),
                    )
                })
                .collect(),
        )
    }

    fn sampling_of(text: &str) -> MethodSpec {
        toml::from_str(text).unwrap()
    }

    /// The sampling method `spec` selects (a panic for any other).
    fn sampling(spec: &MethodSpec) -> &dyn Sampling {
        let Evaluation::Sampling(m) = spec.method().evaluation() else {
            panic!("{spec:?}: a sampling method");
        };
        m
    }

    /// `SobolSampling::estimate` with `data` three rows short of `rows`
    /// panicked (range end index out of range); `Lhs::estimate` with three rows too many or
    /// too few, and `Scm::estimate` with rows that are not design indices, returned `Ok`
    /// with wrong numbers.
    #[test]
    fn estimators_refuse_rows_and_data_that_do_not_match() {
        let inputs = normal_inputs(2);
        for text in [
            "kind = \"sobol_sampling\"\nsamples = 64\nbase = \"mc\"",
            "kind = \"lhs\"\nsamples = 50",
            "kind = \"mc\"\nsamples = 50",
            "kind = \"qmc\"\nsamples = 16",
            "kind = \"scm\"\nnodes = 3",
            "kind = \"nominal\"",
            "kind = \"pce_regression\"\nsamples = 40\norder = 2",
            "kind = \"sparse_grid\"\nlevel = 2",
        ] {
            let spec = sampling_of(text);
            let m = sampling(&spec);
            let design = m.design(&inputs, 7).unwrap();
            let n = design.len();
            let rows: Vec<usize> = (0..n).collect();
            let ok = DMatrix::from_fn(n, 2, |i, j| design.values[i][0] + j as f64);
            m.estimate(&design, &rows, &ok).unwrap();
            let mismatch = |r: Result<Estimate, MethodError>, what: &str| match r {
                Err(MethodError::ResultsMismatch(_)) => {}
                other => panic!("{text}, {what}: {other:?}"),
            };
            if n > 3 {
                let short = ok.rows(0, n - 3).into_owned();
                mismatch(m.estimate(&design, &rows, &short), "data short");
            }
            let long = DMatrix::from_element(n + 3, 2, 1.0);
            mismatch(m.estimate(&design, &rows, &long), "data long");
            let shifted: Vec<usize> = (100..100 + n).collect();
            mismatch(
                m.estimate(&design, &shifted, &ok),
                "rows outside the design",
            );
            if n > 1 {
                let mut twice = rows.clone();
                twice[1] = 0;
                mismatch(m.estimate(&design, &twice, &ok), "a row twice");
            }
        }
    }

    /// `SobolSampling { base: Mc, bootstrap: Some(50), confidence: 2.0 }`
    /// panicked in `estimate` (`partition_at_index`); only `validate` refused it, which
    /// `design` and `estimate` did not call.
    #[test]
    fn sobol_sampling_design_and_estimate_refuse_a_confidence_outside_0_1() {
        let inputs = normal_inputs(2);
        let good = sobol_sampling::SobolSampling {
            samples: 64,
            base: sobol_sampling::Base::Mc,
            replicates: None,
            bootstrap: Some(50),
            confidence: 0.9,
        };
        let design = good.design(&inputs, 3).unwrap();
        let n = design.len();
        let rows: Vec<usize> = (0..n).collect();
        let data = DMatrix::from_fn(n, 1, |i, _| design.values[i][0] + design.values[i][1]);
        for confidence in [2.0, 0.0, 1.0, f64::NAN, -0.5] {
            let bad = sobol_sampling::SobolSampling {
                confidence,
                ..good.clone()
            };
            assert!(
                matches!(bad.design(&inputs, 3), Err(MethodError::Invalid(_))),
                "{confidence}"
            );
            assert!(
                matches!(
                    bad.estimate(&design, &rows, &data),
                    Err(MethodError::Invalid(_))
                ),
                "{confidence}"
            );
        }
    }

    /// `Scm` on an `integer_uniform` input returned `Ok` with std 0.577 (true
    /// 0.816): only `validate` refused a discrete input for a chaos, not `design`/`estimate`.
    #[test]
    fn chaos_methods_refuse_a_discrete_input_in_design_and_estimate() {
        let discrete = RandomInputs::independent(vec![
            RandomParameter::new("n", crate::uq::Distribution::integer_uniform(1, 3).unwrap()),
            RandomParameter::new("x", crate::uq::Distribution::normal(0.0, 1.0).unwrap()),
        ]);
        for text in [
            "kind = \"scm\"\nnodes = 4",
            "kind = \"pce_regression\"\nsamples = 40\norder = 2",
        ] {
            let spec = sampling_of(text);
            let m = sampling(&spec);
            match m.design(&discrete, 1) {
                Err(MethodError::Invalid(e)) => assert!(e.0.contains("integer_uniform"), "{e}"),
                other => panic!("{text}: {other:?}"),
            }
            // A design built for continuous inputs, then given a discrete one (pub fields).
            let mut design = m.design(&normal_inputs(2), 1).unwrap();
            design.inputs = discrete.clone();
            let n = design.len();
            let rows: Vec<usize> = (0..n).collect();
            let data = DMatrix::from_element(n, 1, 1.0);
            assert!(
                matches!(
                    m.estimate(&design, &rows, &data),
                    Err(MethodError::Invalid(_))
                ),
                "{text}"
            );
        }
        // A sampling method takes the discrete input.
        let lhs = sampling_of("kind = \"lhs\"\nsamples = 30");
        let m = sampling(&lhs);
        m.design(&discrete, 1).unwrap();
    }

    /// A `Distribution` struct literal with `low > high` reached the
    /// quantile and panicked (`min > max`); the designs now refuse it with a typed error.
    #[test]
    fn designs_refuse_an_invalid_distribution_literal() {
        let inputs = RandomInputs::independent(vec![RandomParameter {
            name: "u".into(),
            distribution: crate::uq::Distribution::Uniform {
                low: 1.0,
                high: 0.0,
            },
        }]);
        for text in [
            "kind = \"lhs\"\nsamples = 10",
            "kind = \"scm\"\nnodes = 3",
            "kind = \"sobol_sampling\"\nsamples = 16",
            "kind = \"nominal\"",
        ] {
            let spec = sampling_of(text);
            let m = sampling(&spec);
            match m.design(&inputs, 1) {
                Err(e @ MethodError::InvalidInput { .. }) => {
                    assert!(e.to_string().contains("'u'"), "{e}")
                }
                other => panic!("{text}: {other:?}"),
            }
        }
    }
}
