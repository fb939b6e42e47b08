//! A probability counted over runs or draws, with its exact interval, in `summary.json`
//! (`quantities.NAME.exceedance_counts`) and in words.

use serde::Serialize;

use super::{group_digits, numbers, sig};
use crate::uq::method::Draws;

/// Fewer model runs than this beyond a limit: a chaos's count of draws there gets no
/// interval (see [`ExceedanceCount::note_tail`]).
pub(crate) const TAIL_RUNS: usize = 10;

/// P(q > limit) counted over the runs (or the draws of a surrogate).
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct ExceedanceCount {
    /// The limit.
    pub limit: f64,
    /// Draws above it.
    pub exceeded: usize,
    /// Draws in all.
    pub of: usize,
    /// `exceeded / of`.
    pub p: f64,
    /// Clopper–Pearson (exact binomial) 95 % interval of the probability.
    pub ci_95: [f64; 2],
    /// One-sided 95 % upper bound (`1 − 0.05^(1/of)`, about `3/of`, when none exceeded).
    pub upper_95: f64,
    /// What was counted: `runs` or `draws of the chaos surrogate`.
    pub of_what: String,
    /// How `ci_95` and `upper_95` were found: `clopper_pearson` (the draws counted as
    /// independent) or, in a nested study, `outer_bootstrap` (percentile bootstrap over the
    /// outer samples, the independent units; `upper_95` then is the interval's upper end, or
    /// `1 − 0.05^(1/outer_samples)` when none exceeded), `outer_student_t` (Student's t on
    /// the mean of the conditional probabilities, wider than the bootstrap: few outer
    /// samples) or `outer_one_sided` (none exceeded: `[0, 1 − 0.05^(1/outer_samples)]`; all
    /// exceeded: `[0.05^(1/outer_samples), 1]`). Nested: `p` is the mean of the conditional
    /// probabilities, `exceeded` / `of` count every draw of every outer sample.
    pub ci_kind: &'static str,
    /// Nested studies: the number of outer samples the interval rests on.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub outer_samples: Option<usize>,
    /// Counted over the draws of a chaos surrogate with the limit outside the range
    /// `[smallest, largest]` of the model runs: the probability rests on the chaos's
    /// extrapolation alone, which its truncation-error estimate does not cover
    /// (P = 3.7e-4, interval 2.9e-4–4.6e-4, for a true 1e-3 beyond every run of a 4-node SCM).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub beyond_runs: Option<[f64; 2]>,
    /// Counted over the draws of a chaos surrogate with the limit inside the range of the
    /// model runs but only `[k, n]`: `k` of the `n` runs on its failing side (fewer than
    /// 10): the chaos's tail there rests on a handful of runs, which its
    /// truncation-error estimate (an average over the whole range) does not speak for; no
    /// interval is given (`ci_kind` `none_sparse_tail`).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub runs_in_tail: Option<[usize; 2]>,
    /// `above`: the count is of draws above the limit (`P(q > limit)`, the quantity's
    /// `limits`); `below`: below it (`P(q < limit)`, its `limits_below`).
    pub direction: &'static str,
    /// With `beyond_runs` or `runs_in_tail`: the chaos's own design point as the TOML inline
    /// table `{ NAME = VALUE, ... }`, the `centre` of an `importance_sampling` study that
    /// samples the model where the chaos fails (its `chaos_design_point` in `summary.json`).
    #[serde(skip)]
    pub(crate) chaos_centre: Option<String>,
}

impl ExceedanceCount {
    /// How to get the probability from model runs instead of the chaos's tail.
    fn model_runs_instead(&self) -> String {
        match &self.chaos_centre {
            Some(c) => format!(
                "importance_sampling with `centre = {c}`, the chaos's own design point, \
                 estimates it from model runs there"
            ),
            None => "importance_sampling estimates it from model runs".into(),
        }
    }

    /// E.g. `0 of 10 000 runs exceeded 2.5 (95 % upper bound 3.0e-4)` or
    /// `12 of 1 000 runs exceeded 2.5: P = 0.012 (95 % interval 0.0062–0.021)`; nested:
    /// `617 of 2 000 runs over 50 outer samples exceeded 1.5: P = 0.308 (95 % interval, bootstrap
    /// over the outer samples: 0.2–0.42)`.
    ///
    /// Nested studies used to print the Clopper–Pearson interval of the pooled runs, as if
    /// they were independent: it held the true P in 3 of 30 seeds.
    pub fn describe(&self) -> String {
        self.describe_with(&|x: f64| x.to_string())
    }

    /// Sets [`Self::beyond_runs`] when the count is over the `draws` of a chaos and the limit
    /// lies outside `[smallest, largest]`, the range of the model runs. The count's interval
    /// and upper bound are then dropped (but in a nested study, whose interval is over the
    /// outer samples) (NaN, `null` in `summary.json`, `ci_kind`
    /// `none_extrapolation`): the draws' binomial interval says nothing of the chaos's own
    /// error in its tail, which no estimate covers.
    pub fn note_range(&mut self, draws: Draws, [smallest, largest]: [f64; 2]) {
        let outside = self.limit > largest || self.limit < smallest;
        if draws == Draws::Chaos && outside && smallest <= largest {
            self.beyond_runs = Some([smallest, largest]);
            if self.outer_samples.is_some() {
                // Nested: the interval over the outer samples stays (the spread of the
                // tracks); the text names the inner chaoses' extrapolation.
                return;
            }
            self.ci_95 = [f64::NAN; 2];
            self.upper_95 = f64::NAN;
            self.ci_kind = "none_extrapolation";
        }
    }

    /// Sets [`Self::runs_in_tail`] when the count is over the `draws` of a chaos, the limit
    /// lies inside the range of the runs, and fewer than 10 of the `runs` model
    /// runs (`beyond` of them) are on its failing side; the interval and upper bound are
    /// dropped as in [`Self::note_range`]. (A 400-run regression chaos of a smooth lognormal
    /// response with a leave-one-out error of 1.5 % printed 7.0e-4, interval 6.5e-4–7.6e-4,
    /// for an exact 1.0e-3.)
    pub fn note_tail(&mut self, draws: Draws, beyond: usize, runs: usize) {
        if draws == Draws::Chaos && self.beyond_runs.is_none() && beyond < TAIL_RUNS {
            self.runs_in_tail = Some([beyond, runs]);
            self.ci_95 = [f64::NAN; 2];
            self.upper_95 = f64::NAN;
            self.ci_kind = "none_sparse_tail";
        }
    }

    /// Whether the count is of draws below the limit (`P(q < limit)`).
    pub fn is_below(&self) -> bool {
        self.direction == "below"
    }

    /// [`Self::describe`] with the limit (and the range of the runs) written by `value`,
    /// e.g. with its unit: `0 of 20 runs exceeded 1 m (95 % upper bound of P: 0.139)`.
    pub fn describe_with(&self, value: &dyn Fn(f64) -> String) -> String {
        let limit = value(self.limit);
        let outer = self.outer_samples.map_or(String::new(), |k| {
            format!(" over {} outer samples", group_digits(k))
        });
        // "0 of 1 run", not "0 of 1 runs".
        let what = match (self.of, self.of_what.as_str()) {
            (1, "runs") => "run",
            (_, w) => w,
        };
        let head = format!(
            "{} of {} {what}{outer} {} {limit}",
            group_digits(self.exceeded),
            group_digits(self.of),
            if self.is_below() {
                "fell below"
            } else {
                "exceeded"
            }
        );
        let head = match self.beyond_runs {
            Some([_, largest]) if self.limit > largest => format!(
                "{head}, beyond every model run (largest {}): from the chaos's extrapolation \
                 alone",
                value(numbers::rounded(largest, 6))
            ),
            Some([smallest, _]) => format!(
                "{head}, below every model run (smallest {}): from the chaos's extrapolation \
                 alone",
                value(numbers::rounded(smallest, 6))
            ),
            None => head,
        };
        let kind = match (self.outer_samples, self.ci_kind) {
            (Some(_), "outer_student_t") => ", Student's t over the outer samples",
            (Some(_), "outer_one_sided") => ", one-sided, over the outer samples",
            (Some(_), _) => ", bootstrap over the outer samples",
            (None, _) => "",
        };
        if self.ci_kind == "outer_one_sided" && self.exceeded == self.of && self.of > 0 {
            // Nested: every outer sample exceeds; an unsampled one that does not is not ruled
            // out (`0.05^(1/outer_samples)`, [1, 1] from 16 tracks).
            return format!(
                "{head}: P = {} (95 % lower bound of P{kind}: {})",
                sig(self.p),
                sig(self.ci_95[0])
            );
        }
        if let Some([k, n]) = self.runs_in_tail {
            return format!(
                "{head}: P = {}, no interval (only {} of the {} model runs lie beyond the \
                 limit: the chaos's tail there is mostly extrapolation, which its \
                 truncation-error estimate does not cover; {})",
                sig(self.p),
                group_digits(k),
                group_digits(n),
                self.model_runs_instead()
            );
        }
        if self.beyond_runs.is_some() && self.ci_kind == "none_extrapolation" {
            return format!(
                "{head}: P = {}, no interval (the chaos's truncation-error estimate says \
                 nothing of its tail beyond the runs; {})",
                sig(self.p),
                self.model_runs_instead()
            );
        }
        if self.exceeded == 0 {
            format!(
                "{head} (95 % upper bound of P{kind}: {})",
                sig(self.upper_95)
            )
        } else {
            format!(
                "{head}: P = {} (95 % interval{kind}: {}–{})",
                sig(self.p),
                sig(self.ci_95[0]),
                sig(self.ci_95[1])
            )
        }
    }
}
