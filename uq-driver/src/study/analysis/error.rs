//! Why an analysis fails, and the error of a scalar quantity without (enough) values.

use super::QuantityRuns;
use crate::qoi::QoiSpec;
use crate::uq::method::MethodError;

/// Failures of the analysis.
#[derive(Debug, thiserror::Error)]
pub enum AnalysisError {
    /// Too few runs succeeded.
    #[error("only {ok} successful runs: nothing to analyse")]
    TooFewRuns {
        /// Successful runs.
        ok: usize,
    },
    /// The estimator refused an output.
    #[error("output '{name}'")]
    Output {
        /// The output.
        name: String,
        /// Why.
        #[source]
        source: MethodError,
    },
    /// No run gave a value of a quantity.
    #[error(
        "quantity '{name}': no run gave a value ({never_hunts} never hunt, {never_stops} never stop)"
    )]
    NoValue {
        /// The quantity.
        name: String,
        /// Runs that never hunt.
        never_hunts: usize,
        /// Runs whose oscillation never stops.
        never_stops: usize,
    },
    /// The estimator refused a quantity (e.g. a weighted point without a value).
    #[error(
        "quantity '{name}' ({never_hunts} runs never hunt, {never_stops} never stop; use a method \
         that can leave points out, such as LHS or MC, or change the detection settings or the run length)"
    )]
    Quantity {
        /// The quantity.
        name: String,
        /// Runs that never hunt.
        never_hunts: usize,
        /// Runs whose oscillation never stops.
        never_stops: usize,
        /// Why.
        #[source]
        source: MethodError,
    },
    /// A `hunting_speed` quantity whose bracket does not contain the transition at every
    /// point that needs a value (all points, or any point of a weighted design).
    #[error(
        "quantity '{name}': at {decays_at_high} points the disturbance dies out even at the top of \
         the bracket (high = {high}) and at {hunts_at_low} it keeps hunting even at the bottom \
         (low = {low}); widen the bracket{more}"
    )]
    OutsideBracket {
        /// The quantity.
        name: String,
        /// The bracket.
        low: f64,
        /// The bracket.
        high: f64,
        /// Points that die out at `high`.
        decays_at_high: usize,
        /// Points that keep hunting at `low`.
        hunts_at_low: usize,
        /// Further advice.
        more: &'static str,
    },
    /// The results store could not be read.
    #[error(transparent)]
    Store(#[from] crate::study::store::StoreError),
    /// An estimate asks for draws it cannot give.
    #[error("output '{0}': the estimate has neither runs nor a chaos to draw from")]
    NoDraws(String),
}

/// What turns the estimator's refusal of output `name` into the error of the analysis (for
/// `map_err`).
pub(crate) fn output_error(name: &str) -> impl Fn(MethodError) -> AnalysisError + Copy + '_ {
    move |source| AnalysisError::Output {
        name: name.to_owned(),
        source,
    }
}

/// The error of scalar quantity `name` (its runs `qr`) that has no value at any run
/// (`source` `None`) or whose estimator refused its values (`source`, e.g. a weighted design
/// with points left without a value). A `hunting_speed` whose runs missed the transition names
/// its bracket and how many points fell outside it on each side.
pub(crate) fn quantity_error(
    name: &str,
    q: &QoiSpec,
    qr: &QuantityRuns,
    source: Option<MethodError>,
) -> AnalysisError {
    let missed = qr.never_hunts + qr.never_stops > 0;
    match (q, source) {
        (QoiSpec::HuntingSpeed(h), source) if source.is_none() || missed => {
            AnalysisError::OutsideBracket {
                name: name.to_owned(),
                low: h.low,
                high: h.high,
                decays_at_high: qr.never_hunts,
                hunts_at_low: qr.never_stops,
                more: if source.is_some() {
                    " (or use a method that can leave points out, such as LHS or MC)"
                } else {
                    ""
                },
            }
        }
        (_, None) => AnalysisError::NoValue {
            name: name.to_owned(),
            never_hunts: qr.never_hunts,
            never_stops: qr.never_stops,
        },
        (_, Some(source)) => AnalysisError::Quantity {
            name: name.to_owned(),
            never_hunts: qr.never_hunts,
            never_stops: qr.never_stops,
            source,
        },
    }
}
