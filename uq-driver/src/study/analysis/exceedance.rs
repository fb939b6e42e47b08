//! P(q > limit) and P(q < limit) as counts with an exact (Clopper–Pearson) interval, so
//! that "0 of N exceeded" carries its 95 % upper bound instead of a meaningless "0 ± 0"; and
//! the same counts as the `reliability` entries of a quantity.

use crate::results::{ExceedanceCount, LimitProbability};
use crate::uq::method::Draws;
use crate::uq::reliability::Side;

/// `k` of `n` draws above `limit`, with the Clopper–Pearson 95 % interval of the probability
/// (`[0, 1 − 0.025^(1/n)]` two-sided when none exceeds; the one-sided 95 % upper bound
/// `1 − 0.05^(1/n)`, about `3/n`, the rule of three, is given beside it).
#[cfg(test)]
pub fn exceedance_count(draws: &[f64], limit: f64, source: Draws) -> ExceedanceCount {
    count_on_side(draws, limit, Side::Above, source)
}

/// [`exceedance_count`] on either side: `k` of `n` draws above `limit` (`Side::Above`) or
/// below it (`Side::Below`).
pub fn count_on_side(draws: &[f64], limit: f64, side: Side, source: Draws) -> ExceedanceCount {
    let n = draws.len();
    let k = draws
        .iter()
        .filter(|&&x| match side {
            Side::Above => x > limit,
            Side::Below => x < limit,
        })
        .count();
    let (lo, hi) = clopper_pearson(k, n, 0.05);
    ExceedanceCount {
        limit,
        exceeded: k,
        of: n,
        p: if n == 0 {
            f64::NAN
        } else {
            k as f64 / n as f64
        },
        ci_95: [lo, hi],
        upper_95: if n == 0 {
            f64::NAN
        } else if k == 0 {
            1.0 - 0.05f64.powf(1.0 / n as f64)
        } else {
            clopper_pearson(k, n, 0.1).1
        },
        of_what: match source {
            Draws::Runs => "runs".into(),
            Draws::Chaos => "draws of the chaos surrogate".into(),
        },
        ci_kind: "clopper_pearson",
        outer_samples: None,
        beyond_runs: None,
        runs_in_tail: None,
        direction: crate::results::direction(side),
        chaos_centre: None,
    }
}

/// The `reliability` entries of counts (`method`: the study's method kind, for counts over
/// its runs; counts over draws of a chaos are `chaos`).
pub fn counted_probabilities(counts: &[ExceedanceCount], method: &str) -> Vec<LimitProbability> {
    counts
        .iter()
        .map(|e| {
            let side = if e.direction == "below" {
                Side::Below
            } else {
                Side::Above
            };
            let chaos = e.of_what.contains("chaos");
            let ci = e.ci_95.iter().all(|v| v.is_finite()).then_some(e.ci_95);
            let kind = match e.ci_kind {
                "clopper_pearson" if chaos => {
                    "Clopper–Pearson of the draws (the surrogate's own error not included)"
                }
                "clopper_pearson" => "Clopper–Pearson (exact binomial) of the runs",
                "outer_bootstrap" => "percentile bootstrap over the outer samples",
                "outer_student_t" => "Student's t over the outer samples",
                other => other,
            };
            let mut p = LimitProbability::counted(
                e.limit,
                side,
                e.exceeded,
                e.of,
                ci,
                e.upper_95,
                if chaos { "chaos" } else { method },
                kind,
            );
            if e.outer_samples.is_some() {
                p.p = e.p;
            }
            if let Some([k, n]) = e.runs_in_tail {
                p.upper_95 = None;
                p.cov = None;
                p.tail_extrapolated = true;
                p.warnings.push(format!(
                    "counted over draws of the chaos surrogate with only {k} of the {n} model \
                     runs beyond the limit: the chaos's tail there is mostly extrapolation, \
                     which its truncation-error estimate does not cover, so no interval is \
                     given; `importance_sampling` estimates it from model runs"
                ));
            }
            if let (Some([lo, hi]), "none_extrapolation") = (e.beyond_runs, e.ci_kind) {
                // The draws' binomial CoV is not the error of the chaos's tail either.
                p.upper_95 = None;
                p.cov = None;
                p.tail_extrapolated = true;
                p.warnings.push(format!(
                    "counted over draws of the chaos surrogate with the limit outside the range \
                     of the model runs ({lo} to {hi}): the chaos's extrapolation, which its \
                     truncation-error estimate does not cover, so no interval is given; \
                     `importance_sampling` estimates it from model runs"
                ));
            } else if let Some([lo, hi]) = e.beyond_runs {
                p.warnings.push(format!(
                    "counted over draws of the inner chaoses with the limit outside the range \
                     of the model runs ({lo} to {hi}): their extrapolation; the interval covers \
                     the spread over the outer samples, not the chaoses' error in their tails"
                ));
            }
            p
        })
        .collect()
}

/// A nested study's count: the interval and upper bound from the outer samples
/// (`ci`: the percentile bootstrap over them; `outer` of them), not from the pooled draws;
/// `source` says what the pooled values are.
pub fn nest_exceedance_count(
    count: &mut ExceedanceCount,
    ci: [f64; 2],
    outer: usize,
    source: Draws,
) {
    count.ci_95 = ci;
    count.upper_95 = if count.exceeded == 0 && outer > 0 {
        // Each outer sample's first inner value exceeds with probability P, independently.
        1.0 - 0.05f64.powf(1.0 / outer as f64)
    } else {
        ci[1]
    };
    count.ci_kind = "outer_bootstrap";
    count.outer_samples = Some(outer);
    count.of_what = match source {
        Draws::Runs => "runs".into(),
        Draws::Chaos => "draws of the inner chaos surrogates".into(),
    };
}

/// The Clopper–Pearson (exact binomial) interval of level `1 − alpha` for `k` successes in
/// `n` trials; `(NaN, NaN)` for `n = 0`.
pub fn clopper_pearson(k: usize, n: usize, alpha: f64) -> (f64, f64) {
    use statrs::function::beta::inv_beta_reg;
    if n == 0 {
        return (f64::NAN, f64::NAN);
    }
    let (kf, nf) = (k as f64, n as f64);
    let lo = if k == 0 {
        0.0
    } else {
        inv_beta_reg(kf, nf - kf + 1.0, alpha / 2.0)
    };
    let hi = if k == n {
        1.0
    } else {
        inv_beta_reg(kf + 1.0, nf - kf, 1.0 - alpha / 2.0)
    };
    (lo, hi)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_nested_count_takes_the_outer_interval_and_an_outer_upper_bound() {
        // 0 of 4 000 pooled runs from 40 outer samples: the bound rests on the 40 independent
        // outer samples (1 - 0.05^(1/40) = 0.0722), not on 4 000 runs (7.5e-4).
        let mut c = exceedance_count(&vec![0.0; 4000], 1.0, Draws::Runs);
        assert!((c.upper_95 - 7.486e-4).abs() < 1e-6, "{}", c.upper_95);
        nest_exceedance_count(&mut c, [0.0, 0.0], 40, Draws::Chaos);
        assert!((c.upper_95 - (1.0 - 0.05f64.powf(1.0 / 40.0))).abs() < 1e-15);
        assert!((c.upper_95 - 0.0722).abs() < 1e-4);
        assert_eq!(c.ci_kind, "outer_bootstrap");
        assert!(
            c.describe().contains("over 40 outer samples"),
            "{}",
            c.describe()
        );
        assert!(c.describe().contains("bootstrap over the outer samples"));
        let mut c = exceedance_count(&[0.0, 2.0, 3.0, 0.5], 1.0, Draws::Runs);
        nest_exceedance_count(&mut c, [0.1, 0.9], 2, Draws::Runs);
        assert_eq!((c.ci_95, c.upper_95), ([0.1, 0.9], 0.9));
    }

    #[test]
    fn clopper_pearson_matches_published_values() {
        // R: binom.test(5, 20)$conf.int = 0.08657147 0.49104587.
        let (lo, hi) = clopper_pearson(5, 20, 0.05);
        assert!((lo - 0.08657147).abs() < 1e-7 && (hi - 0.49104587).abs() < 1e-7);
        // k = 0: [0, 1 - 0.025^(1/n)]; k = n: [0.025^(1/n), 1].
        let (lo, hi) = clopper_pearson(0, 50, 0.05);
        assert_eq!(lo, 0.0);
        assert!((hi - (1.0 - 0.025f64.powf(1.0 / 50.0))).abs() < 1e-12);
        let (lo, hi) = clopper_pearson(50, 50, 0.05);
        assert!((lo - 0.025f64.powf(1.0 / 50.0)).abs() < 1e-12 && hi == 1.0);
        assert!(clopper_pearson(0, 0, 0.05).0.is_nan());
    }

    #[test]
    fn none_exceeded_reads_as_an_upper_bound() {
        let e = exceedance_count(&[1.0; 1000], 2.5, Draws::Runs);
        assert_eq!((e.exceeded, e.of, e.p), (0, 1000, 0.0));
        assert!((e.upper_95 - (1.0 - 0.05f64.powf(0.001))).abs() < 1e-15);
        assert!((e.upper_95 - 3.0 / 1000.0).abs() < 1e-4, "rule of three");
        let text = e.describe();
        assert!(
            text.starts_with("0 of 1\u{202f}000 runs exceeded 2.5"),
            "{text}"
        );
        assert!(text.contains("95 % upper bound of P: 0.00299"), "{text}");
        assert!(!text.contains('±'));
        let e = exceedance_count(&[1.0, 3.0, 4.0, 0.0], 2.5, Draws::Chaos);
        assert_eq!(e.exceeded, 2);
        let text = e.describe();
        assert!(
            text.contains(
                "2 of 4 draws of the chaos surrogate exceeded 2.5: P = 0.500 (95 % interval"
            ),
            "{text}"
        );
    }
}
