//! Checks of a chaos: against the method's own variance (SCM: the quadrature's), and its own
//! estimate of its truncation error.

use std::collections::BTreeMap;

use super::Analysed;
use crate::report::units::with_unit;
use crate::results::numbers::computed;
use crate::uq::method::pce_regression::FOLDS;
use crate::uq::method::{ChaosError, ChaosErrorKind};
use crate::uq::surrogate::NamedChaos;

/// A chaos whose own truncation-error estimate (relative to the variance) exceeds this at some
/// time, or for a quantity, is reported ([`chaos_error_warnings`]; a nested study's inner
/// chaoses likewise).
pub(crate) const CHAOS_ERROR: f64 = 0.05;

/// A chaos whose variance differs from the method's own by more than this fraction of it
/// (at some time) is reported ([`chaos_gap_warnings`]).
const CHAOS_GAP: f64 = 0.01;

/// Warnings where a method's chaos holds a variance that differs by more than
/// [`CHAOS_GAP`] from the method's own estimate of it (SCM: the quadrature's, from the same
/// runs): the chaos's Sobol' indices, quantiles and densities then miss (or invent) that part,
/// and the quadrature itself may not have converged. `askey_hint`: the design maps inputs
/// that have an Askey family of their own through the normal (`chaos = "hermite"`), so the
/// warning suggests their own families. `units`: the unit of each output and quantity, where
/// known (the Stds are written with it).
pub(crate) fn chaos_gap_warnings(
    a: &Analysed,
    askey_hint: bool,
    units: &BTreeMap<String, String>,
) -> Vec<String> {
    let mut out = Vec::new();
    let unit = |name: &str| units.get(name).map(String::as_str);
    for o in &a.outputs {
        if let Some(sc) = &o.std_pce {
            let column = Column {
                name: &o.name,
                unit: unit(&o.name),
                times: Some(&o.times),
            };
            out.extend(chaos_gap(&column, &o.mean, &o.std, sc, askey_hint));
        }
    }
    for c in &a.quantity_chaos {
        if let Some(q) = a.quantities.iter().find(|q| q.name == c.name) {
            let column = Column {
                name: &q.name,
                unit: unit(&q.name),
                times: None,
            };
            out.extend(chaos_gap(
                &column,
                &[q.mean],
                &[q.std],
                &c.pce.std(),
                askey_hint,
            ));
        }
    }
    out
}

/// What a warning names: an output (with its `times`) or a quantity (`None`), and its unit.
struct Column<'a> {
    name: &'a str,
    unit: Option<&'a str>,
    times: Option<&'a [f64]>,
}

/// A Std at or below this fraction of the magnitude of its mean is rounding: the column is
/// deterministic (an output the inputs do not reach, such as a prescribed speed), and a
/// relative comparison of two such Stds measures nothing (1.5e-14 against 3e-22 read as a
/// gap of 2.7e17 %).
const DETERMINISTIC: f64 = 1e-9;

/// Whether a column of mean `mean` and Std `std` is deterministic to rounding.
fn deterministic(mean: f64, std: f64) -> bool {
    std.abs() <= DETERMINISTIC * mean.abs()
}

/// Whether a column whose Std is `s` is resolved among the columns of Std `std`: above 1e-3
/// of the largest finite Std (below, rounding dominates a relative comparison).
fn resolved(std: &[f64]) -> impl Fn(f64) -> bool {
    let largest = std
        .iter()
        .filter(|s| s.is_finite())
        .fold(0.0_f64, |m, s| m.max(s.abs()));
    move |s| s.abs() > 1e-3 * largest
}

/// Warnings where a chaos's own estimate of its truncation error (`loo`, `level_difference`:
/// relative to the variance; not SCM's `order_difference`) exceeds [`CHAOS_ERROR`] at some time (where
/// the Std is above 1e-3 of its largest) or for a quantity: its mean, Std, quantiles,
/// P(q > limit) and Sobol' indices may then be far off, and any interval printed with them
/// covers only the sampling of the chaos, not this error (a 30-input G function
/// at level 2 gave a mean of 0.013 against 1 with a level difference of 1.45 and no warning).
/// Sparse grids whose rules are not all nested have no estimate: `no_estimate` names why.
pub(crate) fn chaos_error_warnings(a: &Analysed, no_estimate: Option<&str>) -> Vec<String> {
    let mut out = Vec::new();
    let mut missing = false;
    for o in &a.outputs {
        let constant = o
            .mean
            .iter()
            .zip(&o.std)
            .all(|(m, s)| deterministic(*m, *s));
        match &o.chaos_error {
            Some(_) if constant => {}
            Some(e) => {
                if let Some((v, k)) = series_error(e, &o.std).filter(|w| w.0 > CHAOS_ERROR) {
                    out.push(match k {
                        None => top_order_warning(
                            &o.name,
                            " over its series",
                            v,
                            chaos_order(&a.output_chaos, &o.name),
                        ),
                        Some(k) => {
                            let at = o
                                .times
                                .get(k)
                                .map_or(String::new(), |t| format!(" at t = {t} s"));
                            let raw = Some(e.values[k]).filter(|&r| e.check.is_some() && r != v);
                            error_warning(&o.name, &at, e.kind.name(), v, raw)
                        }
                    });
                }
            }
            None => missing |= !constant && o.std.iter().any(|s| *s > 0.0),
        }
    }
    for q in &a.quantities {
        if deterministic(q.mean, q.std) {
            continue;
        }
        match &q.chaos_error {
            Some(e) if e.kind == ChaosErrorKind::OrderDifference.name() => {
                if e.value.is_finite() && e.value > CHAOS_ERROR {
                    let order = chaos_order(&a.quantity_chaos, &q.name);
                    out.push(top_order_warning(&q.name, "", e.value, order));
                }
            }
            Some(e)
                if e.check.unwrap_or(e.value).is_finite()
                    && e.check.unwrap_or(e.value) > CHAOS_ERROR =>
            {
                let v = e.check.unwrap_or(e.value);
                let raw = Some(e.value).filter(|&r| e.check.is_some() && r != v);
                out.push(error_warning(&q.name, "", e.kind, v, raw));
            }
            Some(_) => {}
            None => missing |= q.std > 0.0,
        }
    }
    if let (true, Some(why)) = (missing, no_estimate) {
        out.push(format!(
            "no truncation-error estimate ({why}): nothing says whether this chaos has \
             converged; compare with a study one level higher"
        ));
    }
    out
}

/// The truncation error of a chaos over a series whose Std is `std`, as the warnings judge it:
/// SCM's `order_difference` (the variance share of the top degree; its mean and Std are the
/// quadrature's, so it says whether the chaos itself has converged) over the whole series,
/// weighted by the variance as the Sobol' indices of a series are (no column); any other
/// estimate at its largest over the columns whose Std is resolved (above 1e-3 of the
/// largest), with that column; where the estimate has a [`ChaosError::check`], that is
/// judged instead.
pub(crate) fn series_error(e: &ChaosError, std: &[f64]) -> Option<(f64, Option<usize>)> {
    if e.kind == ChaosErrorKind::OrderDifference {
        let (mut shared, mut total) = (0.0, 0.0);
        for (v, s) in e.values.iter().zip(std) {
            if v.is_finite() && s.is_finite() {
                shared += v * s * s;
                total += s * s;
            }
        }
        return (total > 0.0).then(|| (shared / total, None));
    }
    let resolved = resolved(std);
    e.judged()
        .iter()
        .zip(std)
        .enumerate()
        .filter(|(_, (v, s))| v.is_finite() && resolved(**s))
        .max_by(|a, b| a.1 .0.total_cmp(b.1 .0))
        .map(|(k, (&v, _))| (v, Some(k)))
}

/// The warning of a chaos whose estimated truncation error is `value` (`raw`: the estimate
/// of kind `kind` where `value` is its check and differs from it).
fn error_warning(name: &str, at: &str, kind: &str, value: f64, raw: Option<f64>) -> String {
    let how = match (kind, raw) {
        ("level_difference", Some(raw)) => format!(
            " extrapolated to its own level (the difference between its last two levels, the \
             error of the level below, is {:.1} %)",
            100.0 * raw
        ),
        ("loo", Some(raw)) => format!(
            " by {FOLDS}-fold cross-validation with the basis selected again in each fold \
             (the leave-one-out error, optimistic for a selected basis, says {:.1} %)",
            100.0 * raw
        ),
        _ => String::new(),
    };
    format!(
        "{name}{at}: the chaos's own truncation-error estimate ({kind}) is {:.1} % of the \
         variance{how}: its mean, Std, quantiles, P(q > limit) and Sobol' indices may be far \
         off, and their intervals cover only the sampling of the chaos, not this error; raise \
         the level, order or number of runs",
        100.0 * value
    )
}

/// The warning of a collocation chaos whose terms of the top order hold `share` of its
/// variance (`order_difference`; `at`: where): either the model is a polynomial of that order,
/// or the chaos has not converged. exp(x) on 4 nodes had 7 % there and gave
/// P(q > limit) = 3.7e-4 for a true 1e-3, and a negative 0.1 % quantile of a positive
/// quantity, with no warning.
/// A chaos of order 1 holds all its variance in its top order whatever the model: it is told
/// apart, since the share then says nothing of convergence.
fn top_order_warning(name: &str, at: &str, share: f64, order: Option<usize>) -> String {
    if order == Some(1) {
        return format!(
            "{name}: a chaos of order 1 has all its variance in its top order{at} \
             (order_difference {:.1} %), so it cannot tell whether it has converged: its \
             quantiles, densities, P(q > limit) and Sobol' indices are those of a linear \
             model; an `order` of 2 or more (with `nodes` above it: 2 nodes allow order 1 only) \
             gives a chaos that can judge itself",
            100.0 * share
        );
    }
    format!(
        "{name}: the top order of the chaos holds {:.1} % of its variance{at} \
         (order_difference): unless the model is a polynomial of that order, the chaos has not \
         converged, and its quantiles, densities, P(q > limit) and Sobol' indices may be far \
         off; the mean and Std come from the same nodes and may be off too; raise `nodes` and \
         `order` until this share is small",
        100.0 * share
    )
}

/// The total order of the chaos named `name` among `chaoses`, if it is there.
fn chaos_order(chaoses: &[NamedChaos], name: &str) -> Option<usize> {
    chaoses
        .iter()
        .find(|c| c.name == name)
        .map(|c| c.pce.basis.set().order())
}

/// The warning of one output (`times`) or quantity (`None`) whose Std is `std` by the method
/// and `std_chaos` by its chaos, at the column where they differ most (columns whose Std is
/// below 1e-3 of the largest, or [`deterministic`] by their `mean`, are left out: rounding
/// dominates there).
fn chaos_gap(
    column: &Column,
    mean: &[f64],
    std: &[f64],
    std_chaos: &[f64],
    askey_hint: bool,
) -> Option<String> {
    let resolved = resolved(std);
    let (k, gap) = std
        .iter()
        .zip(std_chaos)
        .zip(mean)
        .enumerate()
        .filter(|(_, ((s, c), m))| {
            s.is_finite() && c.is_finite() && resolved(**s) && !deterministic(**m, **s)
        })
        .map(|(k, ((s, c), _))| (k, (s, c)))
        .map(|(k, (s, c))| (k, (s * s - c * c).abs() / (s * s)))
        .fold(None, |w: Option<(usize, f64)>, (k, g)| match w {
            Some((_, best)) if best >= g => w,
            _ => Some((k, g)),
        })?;
    if gap <= CHAOS_GAP {
        return None;
    }
    let at = column
        .times
        .map_or(String::new(), |t| format!(" at t = {} s", t[k]));
    let (s, c) = (std[k], std_chaos[k]);
    let [c_text, s_text] = <[String; 2]>::try_from(computed(&[c, s])).expect("two numbers");
    let (c_text, s_text) = (
        with_unit(&c_text, column.unit),
        with_unit(&s_text, column.unit),
    );
    Some(format!(
        "{}{at}: the chaos holds {:.1} % {} variance than the method's own estimate \
         (Std {c_text} against {s_text}); its Sobol' indices, quantiles and densities {} that \
         part, and the estimate may not have converged either: raise `order` (below `nodes`) \
         or `nodes`{}",
        column.name,
        100.0 * gap,
        if c < s { "less" } else { "more" },
        if c < s { "miss" } else { "add" },
        if askey_hint {
            ", or expand the bounded inputs in their own families (`chaos = \"askey\"`, \
             the default)"
        } else {
            ""
        },
    ))
}

#[cfg(test)]
mod tests {
    use super::*;

    fn column(name: &str) -> Column<'_> {
        Column {
            name,
            unit: Some("m/s"),
            times: None,
        }
    }

    #[test]
    fn a_deterministic_output_gets_no_chaos_gap_warning_from_rounding_noise() {
        // A prescribed speed of 50 m/s: the quadrature's Std is rounding (1.5e-14), the
        // chaos's another rounding (3e-22).
        let w = chaos_gap(&column("V"), &[50.0], &[1.5e-14], &[3e-22], false);
        assert!(w.is_none(), "{w:?}");
    }

    #[test]
    fn a_real_gap_is_still_reported() {
        let w = chaos_gap(&column("q"), &[50.0], &[2.0], &[1.5], false).expect("a warning");
        assert!(w.contains("less variance"), "{w}");
        assert!(chaos_gap(&column("q"), &[0.0], &[2.0], &[1.99], false).is_none());
        // A Std above the rounding level of its mean is compared, however small.
        assert!(chaos_gap(&column("q"), &[1.0], &[1e-6], &[0.5e-6], false).is_some());
    }
}
