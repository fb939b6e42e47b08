//! What the equally weighted random designs (Monte Carlo, Latin hypercube, quasi-Monte Carlo)
//! share: `samples` points in the open unit cube, mapped through each input's quantile
//! function, optionally `replicates` independent copies of the design, and the sample
//! estimator (mean, unbiased Std, standard error of the mean).
//!
//! Without replicates the standard error is the plain Monte Carlo formula `std / sqrt(n)`:
//! exact for Monte Carlo, an upper bound for a Latin hypercube (Owen 1997: its variance is at
//! most that of Monte Carlo with one point fewer), often a far too pessimistic one. With `R`
//! replicates, point `i` belongs to replicate `i / samples`; the mean is the mean of the
//! replicate means and its standard error `sd(replicate means) / sqrt(R)`, an honest one.

use rayon::prelude::*;

use super::design::Design;
use super::error::{InvalidSettings, MethodError};
use super::estimate::Estimate;
use super::traits::{
    DesignSize, Evaluation, KindNotes, Method, MethodSummary, Problem, RunResults, Sampling,
};
use crate::uq::distributions::Germ;
use crate::uq::random_inputs::RandomInputs;

/// `standard_error` in the method's summary: from independent replicates.
pub(crate) const SE_REPLICATES: &str = "replicates: the spread of the replicate means, \
     sd(replicate means) / sqrt(replicates)";
/// `standard_error` of plain Monte Carlo.
pub(crate) const SE_MONTE_CARLO: &str = "Monte Carlo: std / sqrt(samples)";

/// Points of the unit cube, one coordinate per input each.
pub(crate) type Points = Vec<Vec<f64>>;

/// A method that draws `samples` equally weighted points in the unit cube (per replicate).
pub(crate) trait UnitCubeSample: std::fmt::Debug + Send + Sync {
    /// `kind` in study files.
    const KIND: &'static str;

    /// Said of a convergence plot over the number of runs ([`KindNotes::runs_axis`]).
    const RUNS_AXIS: Option<&'static str> = None;

    /// Number of points (of each replicate).
    fn samples(&self) -> usize;

    /// Number of independent replicates of the design, if replicated.
    fn replicates(&self) -> Option<usize> {
        None
    }

    /// The points of replicate `replicate` (`None`: the design is not replicated): `samples`
    /// points of dimension `d` strictly inside (0, 1), a function of
    /// `(samples, d, seed, replicate)` only.
    fn block(&self, d: usize, seed: u64, replicate: Option<usize>) -> Result<Points, MethodError>;

    /// Checks of the method's own (beyond `samples` >= 2 and `replicates` >= 2).
    fn check(&self, _problem: &Problem) -> Result<(), InvalidSettings> {
        Ok(())
    }

    /// Notes on the design for the user.
    fn notes(&self) -> Vec<String> {
        Vec::new()
    }

    /// What the standard error of the mean is (`standard_error` in summary.json).
    fn standard_error(&self) -> &'static str;
}

impl<T: UnitCubeSample> Method for T {
    fn kind(&self) -> &'static str {
        T::KIND
    }

    fn label(&self, _dim: usize) -> String {
        match self.replicates() {
            Some(r) => format!("{} {}x{r}", T::KIND, self.samples()),
            None => format!("{} {}", T::KIND, self.samples()),
        }
    }

    /// At least two samples (one has no spread) and, if replicated, two replicates.
    fn validate(&self, problem: &Problem) -> Result<(), InvalidSettings> {
        if self.samples() < 2 {
            return Err(InvalidSettings("`samples` must be at least 2".into()));
        }
        if let Some(r) = self.replicates() {
            if r < 2 {
                return Err(InvalidSettings(format!(
                    "`replicates` = {r}: at least 2 independent replicates are needed for a \
                     standard error from their spread"
                )));
            }
        }
        self.check(problem)
    }

    fn summary(&self, _dim: usize) -> MethodSummary {
        let size = DesignSize {
            samples: Some(self.samples()),
            nodes_per_dimension: None,
            order: None,
        };
        let mut summary = MethodSummary::new(T::KIND, &size);
        if let Some(r) = self.replicates() {
            summary.details.insert("replicates".into(), r.into());
        }
        summary
            .details
            .insert("standard_error".into(), self.standard_error().into());
        summary
    }

    fn evaluation(&self) -> Evaluation<'_> {
        Evaluation::Sampling(self)
    }

    fn notes() -> KindNotes {
        KindNotes {
            runs_axis: T::RUNS_AXIS,
            ..KindNotes::default()
        }
    }
}

impl<T: UnitCubeSample> Sampling for T {
    /// Replicate by replicate (point `i` in replicate `i / samples`).
    fn make_design(&self, inputs: &RandomInputs, seed: u64) -> Result<Design, MethodError> {
        let d = inputs.len();
        let points = match self.replicates() {
            None => self.block(d, seed, None)?,
            Some(r) => {
                let blocks = (0..r)
                    .into_par_iter()
                    .map(|k| self.block(d, seed, Some(k)))
                    .collect::<Result<Vec<_>, _>>()?;
                blocks.into_iter().flatten().collect()
            }
        };
        let mut design = Design::mapped(Germ::Uniform, points, None, inputs);
        design.warnings.extend(self.notes());
        Ok(design)
    }

    /// Any subset of the points is a valid (smaller) sample: failed points may be left out.
    fn make_estimate(&self, results: RunResults) -> Result<Estimate, MethodError> {
        let RunResults { rows, data, .. } = results;
        Ok(match self.replicates() {
            None => Estimate::from_sample(data),
            Some(_) => Estimate::from_replicates(data, rows, self.samples()),
        })
    }

    fn planned_runs(&self, _dim: usize) -> Option<f64> {
        Some(self.samples() as f64 * self.replicates().unwrap_or(1) as f64)
    }

    fn draws_from_chaos(&self) -> bool {
        false
    }

    /// Any subset of the points is a sample of the inputs' law (the analysis estimates
    /// first-order Sobol' indices and rank correlations from it).
    fn samples_the_law(&self) -> bool {
        true
    }

    fn replicate_size(&self) -> Option<usize> {
        self.replicates().map(|_| self.samples())
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::uq::distributions::RandomParameter;
    use crate::uq::hd::sobol_seq::Sobol;
    use crate::uq::method::{lhs::Lhs, qmc::Qmc};
    use crate::uq::{sampling, Distribution};

    fn unit_params(d: usize) -> RandomInputs {
        RandomInputs::independent(
            (0..d)
                .map(|i| {
                    RandomParameter::new(format!("u{i}"), Distribution::uniform(0.0, 1.0).unwrap())
                })
                .collect(),
        )
    }

    #[test]
    fn an_unreplicated_latin_hypercube_is_the_design_it_always_was() {
        let lhs: Lhs = toml::from_str("samples = 50").unwrap();
        let design = lhs.design(&unit_params(3), 42).unwrap();
        assert_eq!(design.points, sampling::latin_hypercube(50, 3, 42));
        // And its settings serialize as before (the study hash, hence resumed folders).
        assert_eq!(serde_json::to_string(&lhs).unwrap(), r#"{"samples":50}"#);
    }

    #[test]
    fn replicate_r_is_block_r_of_the_design() {
        let params = unit_params(2);
        let lhs: Lhs = toml::from_str("samples = 20\nreplicates = 3").unwrap();
        let design = lhs.design(&params, 5).unwrap();
        assert_eq!(design.len(), 60);
        for r in 0..3 {
            let block = &design.points[20 * r..20 * (r + 1)];
            // Each block is a Latin hypercube on its own.
            for j in 0..2 {
                let mut strata: Vec<usize> = block.iter().map(|p| (p[j] * 20.0) as usize).collect();
                strata.sort_unstable();
                assert_eq!(strata, (0..20).collect::<Vec<_>>());
            }
        }
        assert_ne!(design.points[..20], design.points[20..40]);
        let qmc: Qmc = toml::from_str("samples = 16").unwrap();
        assert_eq!(qmc.replicates, 8);
        let design = qmc.design(&params, 5).unwrap();
        assert_eq!(design.len(), 128);
        for r in 0..8 {
            let want = Sobol::scrambled(2, 5, r as u64)
                .unwrap()
                .points(0, 16)
                .unwrap();
            assert_eq!(design.points[16 * r..16 * (r + 1)], want[..]);
        }
        assert!(design.warnings.is_empty());
        let odd: Qmc = toml::from_str("samples = 100\nreplicates = 2").unwrap();
        let w = odd.design(&params, 5).unwrap().warnings;
        assert!(
            w[0].contains("not a power of two") && w[0].contains("128"),
            "{w:?}"
        );
    }

    #[test]
    fn one_replicate_is_refused() {
        let params = unit_params(1);
        let problem = Problem {
            parameters: &params,
            outputs: &[],
            quantities: 0,
            times: &[0.0],
            system: None,
            correlation: None,
        };
        for text in ["samples = 8\nreplicates = 1", "samples = 8\nreplicates = 0"] {
            let q: Qmc = toml::from_str(text).unwrap();
            let e = q.validate(&problem).unwrap_err();
            assert!(e.0.contains("at least 2 independent replicates"), "{e}");
            let l: Lhs = toml::from_str(text).unwrap();
            assert!(l.validate(&problem).is_err());
        }
    }

    #[test]
    fn the_summary_says_what_the_standard_error_is() {
        let lhs: Lhs = toml::from_str("samples = 50").unwrap();
        let s = lhs.summary(2);
        assert!(s.details["standard_error"]
            .as_str()
            .unwrap()
            .contains("upper bound"));
        assert!(!s.details.contains_key("replicates"));
        let lhs: Lhs = toml::from_str("samples = 50\nreplicates = 4").unwrap();
        let s = lhs.summary(2);
        assert_eq!(s.details["replicates"], 4);
        assert!(s.details["standard_error"]
            .as_str()
            .unwrap()
            .starts_with("replicates"));
        assert_eq!(lhs.planned_runs(2), Some(200.0));
    }
}
