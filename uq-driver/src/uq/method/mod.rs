//! UQ methods, one module per method. Each owns its design (where the model is run, with
//! which weights) and its estimator (moments, chaos, Sobol' indices from the results).
//!
//! The study runner and the report see a method only through [`Method`]:
//! - a [`Sampling`] method builds a [`Design`] (points in a standard space and their physical
//!   values, optional weights) from the study's random parameters; the runner evaluates the
//!   model at every point; the method's estimator turns a results matrix (points × columns:
//!   the time steps of an output, or one scalar quantity) into an [`Estimate`];
//! - an [`Intrusive`] method solves a projected system itself and returns one [`Estimate`]
//!   per output ([`Solution`]).
//!
//! An [`Estimate`] holds moments per column, optionally a chaos surrogate (evaluable and
//! sampleable), Sobol' indices and standard errors, and says where densities and quantiles
//! are to be drawn from ([`Draws`]).
//!
//! **Adding a method**: write `uq/method/<name>.rs` with a settings struct (serde,
//! `deny_unknown_fields`) that implements [`Method`] and [`Sampling`] or [`Intrusive`], and
//! add one line `<name>::<Type>,` to the `methods!` list below. The study file then accepts
//! `[method] kind = "<type in snake_case>"` with the struct's fields as keys.

mod design;
mod estimate;
mod sample;

use nalgebra::DMatrix;
use serde::{Deserialize, Serialize};

pub use design::Design;
pub use estimate::{Draws, Estimate, Sobol};

use crate::uq::distributions::RandomParameter;
use crate::uq::galerkin::GalerkinError;
use crate::uq::pce::PceError;
use crate::uq::quadrature::QuadratureError;

/// Declares the method modules and the `[method]` table: one line per method.
macro_rules! methods {
    ($($module:ident :: $Type:ident),* $(,)?) => {
        $(pub mod $module;)*

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
        }
    };
}

methods! {
    mc::Mc,
    lhs::Lhs,
    scm::Scm,
    sgm::Sgm,
    nominal::Nominal,
}

/// Settings that make no sense for the study they are in (reported as a study-file error).
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
#[error("{0}")]
pub struct InvalidSettings(pub String);

/// Failures of designs and estimators.
#[derive(Debug, thiserror::Error)]
pub enum MethodError {
    /// A quadrature rule could not be built.
    #[error(transparent)]
    Quadrature(#[from] QuadratureError),
    /// A chaos could not be projected.
    #[error(transparent)]
    Chaos(#[from] PceError),
    /// The Galerkin system could not be assembled or solved.
    #[error(transparent)]
    Galerkin(#[from] GalerkinError),
    /// The settings do not fit the study.
    #[error(transparent)]
    Invalid(#[from] InvalidSettings),
    /// A weighted design lacks results at some of its points.
    #[error(
        "{missing} of {total} weighted points have no value; a weighted design cannot drop a point"
    )]
    MissingPoints {
        /// Points without a value.
        missing: usize,
        /// Points of the design.
        total: usize,
    },
}

/// What a method knows of the study it belongs to.
#[derive(Clone, Copy, Debug)]
pub struct Problem<'a> {
    /// The random parameters, in study order.
    pub parameters: &'a [RandomParameter],
    /// The output variables analysed over time.
    pub outputs: &'a [String],
    /// Number of scalar quantities of interest.
    pub quantities: usize,
    /// Communication points (s).
    pub times: &'a [f64],
    /// The study's `[system]` (the equations of an intrusive method), if any.
    pub system: Option<&'a sgm::SystemSpec>,
}

/// The `method` entry of `summary.json`: the kind and the method's settings and diagnostics.
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct MethodSummary {
    /// `kind` of the study file.
    pub kind: String,
    /// Per method (e.g. `samples`, `nodes_per_dimension`, `order`, `terms`, `definiteness`).
    #[serde(flatten)]
    pub details: serde_json::Map<String, serde_json::Value>,
}

impl MethodSummary {
    /// A summary of `kind` with the fields of `settings` (a struct or map).
    pub fn new(kind: &str, settings: &impl Serialize) -> MethodSummary {
        MethodSummary {
            kind: kind.to_owned(),
            details: details(settings),
        }
    }
}

/// The fields of a struct (or map) as the entries of a JSON object; empty for anything else.
pub fn details(value: &impl Serialize) -> serde_json::Map<String, serde_json::Value> {
    match serde_json::to_value(value) {
        Ok(serde_json::Value::Object(map)) => map,
        _ => serde_json::Map::new(),
    }
}

/// The size of a design as summary.json has always reported it (`null` where it does not apply).
#[derive(Clone, Copy, Debug, Serialize)]
pub(crate) struct DesignSize {
    /// Samples (MC, LHS).
    pub samples: Option<usize>,
    /// Nodes per dimension (tensor grids).
    pub nodes_per_dimension: Option<usize>,
    /// Chaos order.
    pub order: Option<usize>,
}

/// How a method obtains its results.
pub enum Evaluation<'a> {
    /// The model is run at the points of a design.
    Sampling(&'a dyn Sampling),
    /// The method solves its own projected system; the model is not run.
    Intrusive(&'a dyn Intrusive),
}

/// A UQ method as the study runner and the report see it.
pub trait Method: std::fmt::Debug + Send + Sync {
    /// The `kind` in study files and summaries.
    fn kind(&self) -> &'static str;

    /// A short label for tables and logs, e.g. `lhs 1000`, `scm 6^2`, `sgm order 6`
    /// (`dim`: number of random parameters).
    fn label(&self, dim: usize) -> String;

    /// Checks the settings against the study; called once, when the study is loaded.
    fn validate(&self, problem: &Problem) -> Result<(), InvalidSettings>;

    /// The settings written under `method` in `summary.json`.
    fn summary(&self, dim: usize) -> MethodSummary;

    /// Whether the method runs the model at a design or solves its own system.
    fn evaluation(&self) -> Evaluation<'_>;
}

/// A method that runs the model at the points of a design.
pub trait Sampling {
    /// The design for `parameters` (deterministic in `seed`).
    fn design(&self, parameters: &[RandomParameter], seed: u64) -> Result<Design, MethodError>;

    /// Estimates from the results `data` (one row per entry of `rows`, the design indices of
    /// the points that gave a value; one column per time step or quantity).
    fn estimate(
        &self,
        design: &Design,
        rows: &[usize],
        data: &DMatrix<f64>,
    ) -> Result<Estimate, MethodError>;

    /// The fewest successful runs the estimator can work with.
    fn min_runs(&self) -> usize {
        2
    }
}

/// A method that solves a projected (intrusive) system instead of running the model.
pub trait Intrusive {
    /// One estimate per output of `problem`, over its times.
    fn solve(&self, problem: &Problem) -> Result<Solution, MethodError>;
}

/// What an intrusive method returns.
#[derive(Clone, Debug)]
pub struct Solution {
    /// One estimate per output.
    pub outputs: Vec<Estimate>,
    /// Diagnostics for the method's entry in `summary.json`.
    pub details: serde_json::Map<String, serde_json::Value>,
    /// Warnings for the user.
    pub warnings: Vec<String>,
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn kinds_are_the_snake_case_variant_names() {
        let toml_kind = |t: &str| -> MethodSpec { toml::from_str(t).unwrap() };
        for (text, kind) in [
            ("kind = \"mc\"\nsamples = 10", "mc"),
            ("kind = \"lhs\"\nsamples = 10", "lhs"),
            ("kind = \"scm\"\nnodes = 3", "scm"),
            ("kind = \"sgm\"\norder = 2", "sgm"),
            ("kind = \"nominal\"", "nominal"),
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
        let params = [
            RandomParameter {
                name: "K".into(),
                distribution: crate::uq::Distribution::normal(a, s_k).unwrap(),
            },
            RandomParameter {
                name: "C".into(),
                distribution: crate::uq::Distribution::normal(b, t).unwrap(),
            },
        ];
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
            "kind = \"scm\"\nnodes = 3",
            "kind = \"nominal\"",
        ] {
            let spec: MethodSpec = toml::from_str(text).unwrap();
            let Evaluation::Sampling(m) = spec.method().evaluation() else {
                panic!("{text} runs a design");
            };
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
                kind => {
                    let se = e.std_error_mean.as_ref().unwrap()[0];
                    assert!((se - e.std[0] / 20000f64.sqrt()).abs() < 1e-15);
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
        let Evaluation::Sampling(m) = spec.method().evaluation() else {
            panic!("scm runs a design");
        };
        let params = [RandomParameter {
            name: "K".into(),
            distribution: crate::uq::Distribution::normal(1.0, 0.1).unwrap(),
        }];
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
}
