//! The check of a chaos against the method's own variance (SCM: the quadrature's).

use super::Analysed;

/// A chaos whose variance differs from the method's own by more than this fraction of it
/// (at some time) is reported ([`chaos_gap_warnings`]).
const CHAOS_GAP: f64 = 0.01;

/// Warnings where a method's chaos holds a variance that differs by more than
/// [`CHAOS_GAP`] from the method's own estimate of it (SCM: the quadrature's, from the same
/// runs): the chaos's Sobol' indices, quantiles and densities then miss (or invent) that part,
/// and the quadrature itself may not have converged. `askey_hint`: the design maps inputs
/// that have an Askey family of their own through the normal (`chaos = "hermite"`), so the
/// warning suggests their own families.
pub(crate) fn chaos_gap_warnings(a: &Analysed, askey_hint: bool) -> Vec<String> {
    let mut out = Vec::new();
    for o in &a.outputs {
        if let Some(sc) = &o.std_pce {
            out.extend(chaos_gap(&o.name, &o.std, sc, Some(&o.times), askey_hint));
        }
    }
    for c in &a.quantity_chaos {
        if let Some(q) = a.quantities.iter().find(|q| q.name == c.name) {
            out.extend(chaos_gap(&q.name, &[q.std], &c.pce.std(), None, askey_hint));
        }
    }
    out
}

/// The warning of one output (`times`) or quantity (`None`) whose Std is `std` by the method
/// and `std_chaos` by its chaos, at the column where they differ most (columns whose Std is
/// below 1e-3 of the largest are left out: rounding dominates there).
fn chaos_gap(
    name: &str,
    std: &[f64],
    std_chaos: &[f64],
    times: Option<&[f64]>,
    askey_hint: bool,
) -> Option<String> {
    let largest = std
        .iter()
        .filter(|s| s.is_finite())
        .fold(0.0_f64, |m, s| m.max(s.abs()));
    let (k, gap) = std
        .iter()
        .zip(std_chaos)
        .enumerate()
        .filter(|(_, (s, c))| s.is_finite() && c.is_finite() && s.abs() > 1e-3 * largest)
        .map(|(k, (s, c))| (k, (s * s - c * c).abs() / (s * s)))
        .fold(None, |w: Option<(usize, f64)>, (k, g)| match w {
            Some((_, best)) if best >= g => w,
            _ => Some((k, g)),
        })?;
    if gap <= CHAOS_GAP {
        return None;
    }
    let at = times.map_or(String::new(), |t| format!(" at t = {} s", t[k]));
    let (s, c) = (std[k], std_chaos[k]);
    Some(format!(
        "{name}{at}: the chaos holds {:.1} % {} variance than the method's own estimate \
         (Std {c:.6e} against {s:.6e}); its Sobol' indices, quantiles and densities {} that \
         part, and the estimate may not have converged either: raise `order` (below `nodes`) \
         or `nodes`{}",
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
