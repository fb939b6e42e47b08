//! The files a two-level (nested) study adds to its output folder, and their sections of
//! `index.html`:
//! - `<q>_conditional.csv`: per outer sample, its outer values and the conditional mean, Std,
//!   exceedance probabilities (and, where the inner method has them, the chaos Std, the
//!   standard error of the mean, the chaos's own error estimate (`loo`, ...), the
//!   first-order Sobol' indices and the chaos coefficients on the union of the outer
//!   samples' bases, 0 for a term a basis does not keep: every row as long as the header);
//! - `<q>_conditional_exceedance.svg`: the distribution over the outer samples of
//!   P(q > limit | outer), as an empirical CDF per limit;
//! - `<q>_conditional_mean.svg`: the conditional mean ± Std of every outer sample, sorted;
//! - `<V>_split.csv` and `<V>_split.svg`: the marginal mean and Std of an output over time and
//!   its split into the inner and outer parts;
//! - for a suite of nested variants, `variance_split.csv`: one row per variant and quantity.

use crate::report::file_name::stem;
use crate::results::numbers::to_spread;
use std::fmt::Write as _;
use std::path::Path;

use super::csv::{push_field, push_header, push_shortest};
use super::{
    palette, write_bytes, write_columns, Band, LinePlot, ReportError, Section, Series, Table,
};
use crate::results::{ConditionalTable, NestedScalar, OutputSplit, ScalarStats, SuiteSummary};

/// Writes the nested files of a study into `dir` (the plots only if `plots`); returns the
/// sections for `index.html`.
pub fn write(
    dir: &Path,
    quantities: &[ScalarStats],
    splits: &[OutputSplit],
    plots: bool,
) -> Result<Vec<Section>, ReportError> {
    let mut sections = Vec::new();
    for q in quantities {
        let Some(n) = &q.nested else { continue };
        conditional_csv(&dir.join(&n.conditional_csv), &n.conditional)?;
        if !plots {
            continue;
        }
        let mut images = Vec::new();
        if !n.conditional.limits.is_empty() {
            let file = format!("{}_conditional_exceedance.svg", stem(&q.name));
            exceedance_plot(&q.name, &n.conditional).write(&dir.join(&file))?;
            images.push(file);
        }
        let file = format!("{}_conditional_mean.svg", stem(&q.name));
        conditional_mean_plot(&q.name, &n.conditional).write(&dir.join(&file))?;
        images.push(file);
        images.push(n.conditional_csv.clone());
        sections.push(quantity_section(q, n, images));
    }
    for s in splits {
        split_csv(dir, s)?;
        if !plots {
            continue;
        }
        split_plot(s).write(&dir.join(format!("{}_split.svg", stem(&s.name))))?;
        sections.push(Section {
            heading: format!("Two-level split of {} over time", s.name),
            text: format!(
                "Marginal Std of {} over time (over both levels, {} outer samples) and its parts: \
                 the square root of the mean conditional variance (inner parameters) and of the \
                 variance of the conditional means (outer parameters, corrected for the inner \
                 sampling error; drawn as 0 where the correction makes it negative).",
                s.name, s.outer_samples
            ),
            images: vec![
                format!("{}_split.svg", stem(&s.name)),
                format!("{}_split.csv", stem(&s.name)),
            ],
            table: None,
        });
    }
    Ok(sections)
}

/// `a [lo, hi]`, each to the resolution the interval allows (rounded at the second
/// significant digit of its half-width: `115 131 [115 090, 115 170]`, `0.0123 [0.0100, 0.0150]`).
fn with_ci(x: f64, ci: [f64; 2]) -> String {
    let half = (ci[1] - ci[0]).abs() / 2.0;
    format!(
        "{} [{}, {}]",
        to_spread(x, half),
        to_spread(ci[0], half),
        to_spread(ci[1], half)
    )
}

/// What the row label says of an interval that is not the bootstrap: `ci_kind` in words.
fn kind_note(kind: &str) -> &'static str {
    match kind {
        "outer_student_t" => " (interval: Student's t, wider than the bootstrap)",
        "outer_one_sided" => " (interval: one-sided 95 % bound over the outer samples)",
        _ => "",
    }
}

fn quantity_section(q: &ScalarStats, n: &NestedScalar, images: Vec<String>) -> Section {
    let v = &n.variance_split;
    let t = &n.conditional;
    let mut rows = vec![
        vec![
            format!("mean{}", kind_note(n.mean_ci_kind)),
            with_ci(q.mean, n.mean_ci),
        ],
        vec!["Std".into(), with_ci(q.std, n.std_ci)],
        vec![
            format!("inner share of Var ({})", t.inner_names.join(", ")),
            with_ci(v.inner, v.inner_ci),
        ],
        vec![
            format!("outer share of Var ({})", t.outer_names.join(", ")),
            with_ci(v.outer, v.outer_ci),
        ],
        vec!["E_outer[Var_inner]".into(), format!("{:.4e}", v.var_inner)],
        vec![
            "Var_outer[E_inner] (corrected; plug-in; correction)".into(),
            format!(
                "{:.4e}; {:.4e}; {:.4e}",
                v.var_outer, v.var_outer_plugin, v.correction
            ),
        ],
    ];
    for e in &n.exceedance_ci {
        rows.push(vec![
            format!("P({} > {}){}", q.name, e.limit, kind_note(e.ci_kind)),
            with_ci(e.p, e.ci),
        ]);
        rows.push(vec![
            format!("P({} > {} | outer): min, median, max", q.name, e.limit),
            format!(
                "{:.4}, {:.4}, {:.4}",
                e.conditional_min, e.conditional_median, e.conditional_max
            ),
        ]);
    }
    Section {
        heading: format!("Two-level split of {}", q.name),
        text: format!(
            "{} over both levels: {} outer samples ({}), each with the inner method over {}. \
             Var = E_outer[Var_inner] + Var_outer[E_inner]; the second term is the sample \
             variance of the conditional means less the mean squared standard error of those \
             means (the inner sampling error; none for collocation or chaos). P(q > limit) is \
             the mean of the conditional probabilities (the quantity's count line gives the \
             same number: it counts every draw of every outer sample). Intervals: {}. The plots: how \
             P(q > limit | outer) spreads over the outer samples (its empirical distribution \
             function, one step per outer sample: steps near 0 and 1 mean the outer parameters \
             decide the exceedance, steps in between that the inner ones do), and the \
             conditional mean ± Std of every outer sample, sorted by the mean.",
            q.name,
            n.outer_samples,
            t.outer_names.join(", "),
            t.inner_names.join(", "),
            n.intervals
        ),
        images,
        table: Some(Table::new(&["statistic", "value [95 % interval]"], rows)),
    }
}

/// The column name of a limit's conditional probability: `p_exceed_2.5`.
pub fn exceed_column(limit: f64) -> String {
    let mut s = String::from("p_exceed_");
    push_shortest(&mut s, limit);
    s
}

/// `<q>_conditional.csv`.
fn conditional_csv(path: &Path, t: &ConditionalTable) -> Result<(), ReportError> {
    let mut header: Vec<String> = vec!["outer".into()];
    header.extend(t.outer_names.iter().cloned());
    header.extend(["runs", "mean", "std"].map(String::from));
    if t.std_chaos.is_some() {
        header.push("std_chaos".into());
    }
    if t.std_error_mean.is_some() {
        header.push("std_error_mean".into());
    }
    if let Some((name, _)) = &t.chaos_error {
        header.push(name.clone());
    }
    header.extend(t.limits.iter().map(|&l| exceed_column(l)));
    if t.sobol_first.is_some() {
        header.extend(t.inner_names.iter().map(|n| format!("S_{n}")));
    }
    if let Some((indices, _)) = &t.chaos {
        header.extend(indices.iter().map(|k| {
            let k: Vec<String> = k.iter().map(usize::to_string).collect();
            format!("c_{}", k.join("_"))
        }));
    }
    let mut text = String::new();
    push_header(
        &mut text,
        &header.iter().map(String::as_str).collect::<Vec<_>>(),
    );
    for r in 0..t.mean.len() {
        let mut row: Vec<f64> = t.outer_values[r].clone();
        row.extend([t.runs[r] as f64, t.mean[r], t.std[r]]);
        row.extend(t.std_chaos.as_ref().map(|s| s[r]));
        row.extend(t.std_error_mean.as_ref().map(|s| s[r]));
        row.extend(t.chaos_error.as_ref().map(|(_, e)| e[r]));
        row.extend(t.exceedance.iter().map(|p| p[r]));
        if let Some(s) = &t.sobol_first {
            row.extend(&s[r]);
        }
        if let Some((_, c)) = &t.chaos {
            row.extend(&c[r]);
        }
        let _ = write!(text, "{}", t.outer_index[r]);
        for v in row {
            text.push(',');
            push_shortest(&mut text, v);
        }
        text.push('\n');
    }
    write_bytes(path, text.as_bytes())
}

/// The empirical CDF of `P(q > limit | outer)` over the outer samples, one curve per limit.
fn exceedance_plot(name: &str, t: &ConditionalTable) -> LinePlot {
    let mut plot = LinePlot::new(
        format!("{name}: distribution over the outer samples of P({name} > limit | outer)"),
        format!("P({name} > limit | outer)"),
        "fraction of outer samples at or below",
    );
    for (l, (limit, p)) in t.limits.iter().zip(&t.exceedance).enumerate() {
        let mut sorted = p.clone();
        sorted.sort_by(f64::total_cmp);
        let n = sorted.len() as f64;
        let (mut x, mut y) = (vec![0.0], vec![0.0]);
        for (i, v) in sorted.iter().enumerate() {
            x.extend([*v, *v]);
            y.extend([i as f64 / n, (i + 1) as f64 / n]);
        }
        x.push(1.0);
        y.push(1.0);
        plot.series
            .push(Series::new(format!("limit {limit}"), x, y, palette(l)));
    }
    plot
}

/// The conditional mean ± Std of every outer sample, sorted by the mean.
fn conditional_mean_plot(name: &str, t: &ConditionalTable) -> LinePlot {
    let mut order: Vec<usize> = (0..t.mean.len()).collect();
    order.sort_by(|&a, &b| t.mean[a].total_cmp(&t.mean[b]));
    let x: Vec<f64> = (1..=order.len()).map(|i| i as f64).collect();
    let mean: Vec<f64> = order.iter().map(|&k| t.mean[k]).collect();
    let lower: Vec<f64> = order.iter().map(|&k| t.mean[k] - t.std[k]).collect();
    let upper: Vec<f64> = order.iter().map(|&k| t.mean[k] + t.std[k]).collect();
    let mut plot = LinePlot::new(
        format!("{name}: conditional mean ± Std per outer sample (sorted)"),
        "outer sample (rank of the conditional mean)",
        name.to_string(),
    );
    plot.bands.push(Band::new(
        "conditional mean ± Std (inner spread)",
        x.clone(),
        lower,
        upper,
        palette(0),
    ));
    plot.series
        .push(Series::new("conditional mean", x.clone(), mean, palette(0)));
    for (l, &limit) in t.limits.iter().enumerate() {
        let ends = vec![x[0], x[x.len() - 1]];
        plot.series.push(
            Series::new(
                format!("limit {limit}"),
                ends,
                vec![limit; 2],
                palette(l + 3),
            )
            .dashed(),
        );
    }
    plot
}

/// `<V>_split.csv`: `time,mean,std,var_inner,var_outer,inner_fraction,outer_fraction`.
fn split_csv(dir: &Path, s: &OutputSplit) -> Result<(), ReportError> {
    let (fi, fo): (Vec<f64>, Vec<f64>) = s
        .var_inner
        .iter()
        .zip(&s.var_outer)
        .map(|(&i, &o)| {
            let t = i + o.max(0.0);
            if t > 0.0 {
                (i / t, o.max(0.0) / t)
            } else {
                (0.0, 0.0)
            }
        })
        .unzip();
    write_columns(
        &dir.join(format!("{}_split.csv", stem(&s.name))),
        &[
            "time",
            "mean",
            "std",
            "var_inner",
            "var_outer",
            "inner_fraction",
            "outer_fraction",
        ],
        &[
            &s.times,
            &s.mean,
            &s.std,
            &s.var_inner,
            &s.var_outer,
            &fi,
            &fo,
        ],
    )
}

/// `<V>_split.svg`: the marginal Std over time and its inner and outer parts.
fn split_plot(s: &OutputSplit) -> LinePlot {
    let root = |v: &[f64]| -> Vec<f64> { v.iter().map(|x| x.max(0.0).sqrt()).collect() };
    let mut plot = LinePlot::new(
        format!("{}: Std over both levels and its parts", s.name),
        "time [s]",
        format!("Std {}", s.name),
    );
    plot.series = vec![
        Series::new(
            "Std (both levels)",
            s.times.clone(),
            s.std.clone(),
            palette(0),
        ),
        Series::new(
            "sqrt E_outer[Var_inner] (inner)",
            s.times.clone(),
            root(&s.var_inner),
            palette(1),
        ),
        Series::new(
            "sqrt Var_outer[E_inner] (outer)",
            s.times.clone(),
            root(&s.var_outer),
            palette(2),
        ),
    ];
    plot
}

/// `variance_split.csv` of a suite whose variants are nested studies: per variant and
/// quantity the marginal mean, Std and exceedance probabilities and the split, each with its
/// interval; `None` when no variant is nested.
pub fn write_suite(dir: &Path, summary: &SuiteSummary) -> Result<Option<String>, ReportError> {
    let mut text = String::from(
        "variant,quantity,mean,mean_lo,mean_hi,std,std_lo,std_hi,inner,inner_lo,inner_hi,\
         outer,outer_lo,outer_hi,std_inner,std_outer,limit,p,p_lo,p_hi,p_conditional_min,\
         p_conditional_median,p_conditional_max\n",
    );
    let mut any = false;
    for v in &summary.variants {
        for q in &v.quantities {
            let Some(n) = &q.nested else { continue };
            any = true;
            let s = &n.variance_split;
            let head = [
                q.mean,
                n.mean_ci[0],
                n.mean_ci[1],
                q.std,
                n.std_ci[0],
                n.std_ci[1],
                s.inner,
                s.inner_ci[0],
                s.inner_ci[1],
                s.outer,
                s.outer_ci[0],
                s.outer_ci[1],
                s.var_inner.max(0.0).sqrt(),
                s.var_outer.max(0.0).sqrt(),
            ];
            let limits: Vec<Option<&crate::results::ExceedanceInterval>> =
                if n.exceedance_ci.is_empty() {
                    vec![None]
                } else {
                    n.exceedance_ci.iter().map(Some).collect()
                };
            for e in limits {
                push_field(&mut text, &v.name);
                text.push(',');
                push_field(&mut text, &q.name);
                let tail = e.map_or([f64::NAN; 6], |e| {
                    [
                        e.limit,
                        e.p,
                        e.ci[0],
                        e.ci[1],
                        e.conditional_min,
                        e.conditional_median,
                    ]
                });
                for x in head.iter().chain(&tail) {
                    text.push(',');
                    push_shortest(&mut text, *x);
                }
                text.push(',');
                push_shortest(&mut text, e.map_or(f64::NAN, |e| e.conditional_max));
                text.push('\n');
            }
        }
    }
    if !any {
        return Ok(None);
    }
    let file = "variance_split.csv".to_string();
    write_bytes(&dir.join(&file), text.as_bytes())?;
    Ok(Some(file))
}

/// The section of a suite's `index.html` for nested variants: per variant and quantity the
/// marginal Std and exceedance probabilities with their intervals, the split into the inner
/// and outer parts, and the published values where the suite gives them; `None` when no
/// variant is nested.
pub fn suite_section(summary: &SuiteSummary) -> Option<Section> {
    let paper = |variant: &str, quantity: &str, statistic: &str| -> String {
        summary
            .paper
            .iter()
            .find(|p| p.variant == variant && p.quantity == quantity && p.statistic == statistic)
            .map_or_else(String::new, |p| format!("{}", p.value))
    };
    let mut rows = Vec::new();
    for v in &summary.variants {
        for q in &v.quantities {
            let Some(n) = &q.nested else { continue };
            let s = &n.variance_split;
            let head = vec![
                v.name.clone(),
                q.name.clone(),
                with_ci(q.mean, n.mean_ci),
                with_ci(q.std, n.std_ci),
                paper(&v.name, &q.name, "std"),
                format!("{:.4}", s.var_inner.max(0.0).sqrt()),
                format!("{:.4}", s.var_outer.max(0.0).sqrt()),
                with_ci(s.inner, s.inner_ci),
                with_ci(s.outer, s.outer_ci),
            ];
            if n.exceedance_ci.is_empty() {
                rows.push(head.clone());
            }
            for e in &n.exceedance_ci {
                let mut row = head.clone();
                row.push(format!("{}", e.limit));
                row.push(with_ci(e.p, e.ci));
                row.push(format!(
                    "{:.4} [{:.4}, {:.4}]",
                    e.conditional_median, e.conditional_min, e.conditional_max
                ));
                row.push(paper(&v.name, &q.name, &format!("p>{}", e.limit)));
                rows.push(row);
            }
        }
    }
    if rows.is_empty() {
        return None;
    }
    Some(Section {
        heading: "Two-level split".into(),
        text: "Each nested variant over both levels (95 % intervals over the outer samples: \
               bootstrap, for the Std and the shares joined with Student's t from the \
               jackknife): the marginal mean and Std; the Std's two parts, the root of the mean \
               conditional variance (the inner parameters alone, e.g. the vehicle) and of the \
               variance of the conditional means (the outer parameters, e.g. the track); their \
               shares of the variance; P(q > limit) over both levels (the mean of the \
               conditional probabilities) and how P(q > limit | outer) spreads over the outer \
               samples (median [min, max]); beside the published values where the suite gives \
               them (see the suite's description for what those were computed on)."
            .into(),
        images: vec!["variance_split.csv".into()],
        table: Some(Table::new(
            &[
                "variant",
                "quantity",
                "mean",
                "Std",
                "Std (paper)",
                "√E[Var inner]",
                "√Var[E inner] (outer)",
                "inner share",
                "outer share",
                "limit",
                "P(q > limit)",
                "P(q > limit | outer): median [min, max]",
                "P (paper)",
            ],
            rows,
        )),
    })
}

#[cfg(test)]
mod tests {
    use super::with_ci;

    #[test]
    fn intervals_read_to_their_own_resolution() {
        // Four fixed decimals whatever the size ("115131.0736 [...]").
        assert_eq!(
            with_ci(115131.0736, [115090.2, 115170.9]),
            "115\u{202f}131 [115\u{202f}090, 115\u{202f}171]"
        );
        assert_eq!(with_ci(0.0123, [0.01, 0.015]), "0.0123 [0.0100, 0.0150]");
    }
}
