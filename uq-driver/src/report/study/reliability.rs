//! The section of a quantity of a reliability or screening study: β and P with their
//! intervals (a table per limit), the importance factors as bars, the design point against
//! the nominal point, the convergence of importance sampling and subset simulation (P
//! against runs), and Morris's μ* and σ as ranked bars.

use std::collections::BTreeMap;
use std::path::Path;

use super::super::svg::{BarChart, BarGroup};
use super::super::units::with_unit;
use super::super::{palette, Band, LinePlot, ReportError, Section, Series};
use crate::report::file_name::stem;
use crate::results::numbers::count;
use crate::results::{sig, LimitProbability, MorrisScreening, ScalarStats, Summary};

/// Whether the study is a reliability or screening study (its runs are not samples of the
/// inputs' law: no density or moments).
pub(super) fn is_adaptive(summary: &Summary) -> bool {
    crate::uq::method::notes_of_kind(&summary.method.kind).adaptive
}

/// The section of quantity `q` of a reliability or screening study.
pub(super) fn section(
    dir: &Path,
    q: &ScalarStats,
    summary: &Summary,
    names: &[&str],
) -> Result<Section, ReportError> {
    let name = &q.name;
    let unit = q.unit.as_deref();
    let mut images = Vec::new();
    let mut text = format!("{name}: {}.", q.definition.text);
    let mut rows = Vec::new();
    for (k, r) in q.reliability.iter().flatten().enumerate() {
        let label = r.label(name);
        text.push_str(&format!("\n\n{}", sentence(r, &label, unit)));
        rows.extend(limit_rows(r, &label, summary, names));
        let tag = format!("{}_{}", stem(name), k + 1);
        if let Some(imp) = &r.importance {
            importance_bars(dir, &tag, &label, imp, correlated_gamma(r), names)?;
            images.push(format!("{tag}_importance.svg"));
        }
        if convergence(dir, &tag, &label, r)? {
            images.push(format!("{tag}_convergence.svg"));
        }
        for w in &r.warnings {
            text.push_str(&format!("\n\nWarning: {w}"));
        }
    }
    if let Some(m) = &q.morris {
        morris_bars(dir, name, m)?;
        images.push(format!("{}_morris.svg", stem(name)));
        text.push_str(&format!(
            "\n\nMorris screening: μ* (the mean absolute elementary effect, the ranking) and σ \
             (their standard deviation: non-linearity and interactions) per input, per unit of \
             probability level (the change of {name} when the input moves across its whole \
             distribution). Largest first: {}.",
            m.ranking.join(", ")
        ));
        for w in &m.warnings {
            text.push_str(&format!("\n\nWarning: {w}"));
        }
        rows.extend(m.ranking.iter().map(|n| {
            vec![
                format!("Morris μ* / σ of {n}"),
                format!("{} / {}", sig(m.mu_star[n]), sig(m.sigma[n])),
            ]
        }));
    }
    if q.reliability.is_none() && q.morris.is_none() {
        text.push_str(&format!(
            "\n\nNo probability of {name} was asked of the method (no `limits` or \
             `limits_below`, or not among the method's `quantities`): only the range of its \
             values over the runs is shown."
        ));
    }
    if q.n_valid > 0 {
        rows.push(vec![
            format!("{name} over the runs (not a sample of its law)"),
            format!(
                "{} to {} ({})",
                with_unit(&sig(q.min), unit),
                with_unit(&sig(q.max), unit),
                count(q.n_valid, "valid run", "valid runs")
            ),
        ]);
    }
    Ok(super::quantity_table(name, text, images, rows))
}

/// `P(q > 6) = 2.15e-3 (95 % interval 1.95e-3–2.36e-3, CoV 4.9 %), β = 2.85, by
/// importance sampling in 1 645 runs.`
fn sentence(r: &LimitProbability, label: &str, unit: Option<&str>) -> String {
    let mut s = format!("{label} = {}", sig(r.p));
    if let Some([lo, hi]) = r.ci_95 {
        s.push_str(&format!(" (95 % interval {}–{}", sig(lo), sig(hi)));
        if let Some(c) = r.cov_words() {
            s.push_str(&format!(", {c}"));
        }
        s.push(')');
    } else if let Some(u) = r.upper_95 {
        s.push_str(&format!(" (95 % upper bound {})", sig(u)));
    } else if matches!(r.method.as_str(), "form" | "sorm") {
        s.push_str(
            " (an approximation without an error estimate: importance_sampling corrects it)",
        );
    }
    if let Some(b) = r.beta {
        s.push_str(&format!(", β = {b:.3}"));
    }
    s.push_str(&format!(
        ", by {} in {}; the limit is {}.",
        r.method.replace('_', " "),
        count(r.runs, "model run", "model runs"),
        with_unit(&r.limit.to_string(), unit)
    ));
    s
}

/// Table rows of one probability: P, its interval, β, runs, and per input the nominal
/// value (the median: the origin of the standard normal space), the design point and α².
fn limit_rows(
    r: &LimitProbability,
    label: &str,
    summary: &Summary,
    names: &[&str],
) -> Vec<Vec<String>> {
    let mut rows = vec![vec![label.to_owned(), sig(r.p)]];
    if let Some([lo, hi]) = r.ci_95 {
        rows.push(vec![
            format!("{label}: 95 % interval"),
            format!("{}–{}", sig(lo), sig(hi)),
        ]);
    }
    if let Some(c) = r.cov {
        rows.push(vec![format!("{label}: CoV"), format!("{:.1} %", 100.0 * c)]);
    }
    if let Some(u) = r.upper_95 {
        rows.push(vec![format!("{label}: 95 % upper bound"), sig(u)]);
    }
    if let Some(b) = r.beta {
        rows.push(vec![format!("{label}: β"), format!("{b:.4}")]);
    }
    rows.push(vec![
        format!("{label}: method, runs"),
        format!("{}, {}", r.method, r.runs),
    ]);
    if let Some(x) = &r.design_point {
        for (n, p) in names.iter().zip(&summary.parameters) {
            let unit = summary.units.get(*n).map(String::as_str);
            let median = p.distribution.inverse_cdf(0.5);
            let mut imp = r
                .importance
                .as_ref()
                .and_then(|i| i.get(*n))
                .map_or(String::new(), |a| format!(", α² = {}", sig(*a)));
            if let Some(g) = correlated_gamma(r).and_then(|g| g.get(*n)) {
                imp.push_str(&format!(", γ² = {}", sig(*g)));
            }
            rows.push(vec![
                format!("{label}: design point {n} (nominal: median)"),
                format!(
                    "{} (nominal {}){imp}",
                    with_unit(&sig(x[*n]), unit),
                    with_unit(&sig(median), unit)
                ),
            ]);
        }
    }
    rows
}

/// The inputs' importance `γ²` where it differs from `α²` (correlated inputs).
fn correlated_gamma(r: &LimitProbability) -> Option<&BTreeMap<String, f64>> {
    r.importance_gamma
        .as_ref()
        .filter(|g| Some(*g) != r.importance.as_ref())
}

/// `<q>_<k>_importance.svg`: FORM's importance factors α² per input, largest first, and
/// beside them the inputs' importance γ² when the inputs are correlated.
fn importance_bars(
    dir: &Path,
    tag: &str,
    label: &str,
    importance: &BTreeMap<String, f64>,
    gamma: Option<&BTreeMap<String, f64>>,
    names: &[&str],
) -> Result<(), ReportError> {
    let value = |m: &BTreeMap<String, f64>, n: &str| m.get(n).copied().unwrap_or(f64::NAN);
    let mut order: Vec<(&str, f64)> = names.iter().map(|n| (*n, value(importance, n))).collect();
    order.sort_by(|a, b| b.1.total_cmp(&a.1));
    let mut groups = vec![BarGroup {
        label: "α²".into(),
        color: palette(0).into(),
        values: order.iter().map(|(_, v)| *v).collect(),
        intervals: vec![None; order.len()],
    }];
    if let Some(g) = gamma {
        groups.push(BarGroup {
            label: "γ² (the inputs, with their correlation)".into(),
            color: palette(1).into(),
            values: order.iter().map(|(n, _)| value(g, n)).collect(),
            intervals: vec![None; order.len()],
        });
    }
    let y_label = match gamma {
        None => "α² (share of β²) [-]",
        Some(_) => "α² (share of β²), γ² [-]",
    };
    BarChart {
        title: format!("{label}: importance factors at the design point"),
        y_label: y_label.into(),
        x_label: "parameter".into(),
        categories: order.iter().map(|(n, _)| n.to_string()).collect(),
        groups,
        y_range: Some((0.0, 1.0)),
        interval_label: String::new(),
    }
    .write(&dir.join(format!("{tag}_importance.svg")))
}

/// `<q>_<k>_convergence.svg`: P against runs with its 95 % band (importance sampling: the
/// running estimate; subset simulation: the product of the levels' conditional
/// probabilities against the runs at the end of each level). False when the method has no
/// such history.
fn convergence(
    dir: &Path,
    tag: &str,
    label: &str,
    r: &LimitProbability,
) -> Result<bool, ReportError> {
    let Some(res) = r.result.as_deref() else {
        return Ok(false);
    };
    let (x, p, cov, what): (Vec<f64>, Vec<f64>, Vec<Option<f64>>, &str) =
        if let Some(is) = &res.importance_sampling {
            (
                is.history.iter().map(|h| h.runs as f64).collect(),
                is.history.iter().map(|h| h.probability).collect(),
                is.history.iter().map(|h| h.cov).collect(),
                "importance sampling",
            )
        } else if let Some(ss) = &res.subset {
            let (mut runs, mut prod, mut var) = (0.0, 1.0, 0.0);
            let mut out = (Vec::new(), Vec::new(), Vec::new());
            for l in &ss.levels {
                runs += l.runs as f64;
                prod *= l.conditional_probability;
                var += l.cov * l.cov;
                out.0.push(runs);
                out.1.push(prod);
                out.2.push(Some(var.sqrt()));
            }
            (out.0, out.1, out.2, "subset simulation, level by level")
        } else {
            return Ok(false);
        };
    if x.len() < 2 {
        return Ok(false);
    }
    let band = |sign: f64| -> Vec<f64> {
        p.iter()
            .zip(&cov)
            .map(|(p, c)| c.map_or(f64::NAN, |c| p * (sign * 1.96 * c).exp()))
            .collect()
    };
    let mut plot = LinePlot::new(format!("{label}: convergence ({what})"), "model runs", "P");
    plot.log_y = true;
    plot.bands.push(Band::new(
        "95 % band (log-normal, estimated CoV)",
        x.clone(),
        band(-1.0),
        band(1.0),
        palette(0),
    ));
    let mut series = Series::new("P", x, p, palette(0));
    if res.subset.is_some() {
        series = series.with_markers();
    }
    plot.series.push(series);
    plot.write(&dir.join(format!("{tag}_convergence.svg")))?;
    Ok(true)
}

/// `<q>_morris.svg`: μ* and σ per input, ranked by μ*.
fn morris_bars(dir: &Path, name: &str, m: &MorrisScreening) -> Result<(), ReportError> {
    let pick = |map: &std::collections::BTreeMap<String, f64>| -> Vec<f64> {
        m.ranking.iter().map(|n| map[n]).collect()
    };
    BarChart {
        title: format!("{name}: Morris screening, inputs ranked by μ*"),
        y_label: format!("elementary effect of {name} per unit of probability level"),
        x_label: "parameter".into(),
        categories: m.ranking.clone(),
        groups: vec![
            BarGroup {
                label: "μ* (mean |EE|)".into(),
                color: palette(0).into(),
                values: pick(&m.mu_star),
                intervals: vec![None; m.ranking.len()],
            },
            BarGroup {
                label: "σ (std of EE)".into(),
                color: palette(1).into(),
                values: pick(&m.sigma),
                intervals: vec![None; m.ranking.len()],
            },
        ],
        y_range: None,
        interval_label: String::new(),
    }
    .write(&dir.join(format!("{}_morris.svg", stem(name))))
}
