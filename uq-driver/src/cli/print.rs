//! What `run` prints about a finished study or suite.

use std::path::Path;

use crate::report::units::with_unit;
use crate::results::numbers::{count, to_spread};
use crate::results::{sig, ScalarStats};
use crate::study::{StudyResult, SuiteResult};

/// The result of `run` on the terminal: runs, wall time, the scalar quantities, warnings;
/// where the results are (`index.html`, or the folder when `--no-report` wrote no page).
pub(crate) fn print_study(r: &StudyResult, out: &Path, no_report: bool) {
    let s = &r.summary;
    for w in s.warnings.iter().skip(r.warnings_shown) {
        eprintln!("uq-driver: warning: {w}");
    }
    let t = &s.timing;
    let runs = if s.fmu.is_none() {
        // An intrusive method (SGM): its own system, solved once; no model run.
        "the Galerkin system solved once".to_owned()
    } else {
        format!(
            "{} ({} resumed)",
            count(s.model_runs, "model run", "model runs"),
            s.runs_resumed
        )
    };
    println!(
        "{}: {runs}; wall time: runs {:.2} s, analysis {:.2} s, report {:.2} s; {}",
        s.study,
        t.runs_s,
        t.analysis_s,
        t.report_s,
        if no_report {
            format!(
                "results: {} (CSV files and summary.json only, --no-report)",
                out.display()
            )
        } else {
            format!("report: {}", out.join("index.html").display())
        }
    );
    let nominal = crate::uq::method::notes_of_kind(&s.method.kind).deterministic;
    for q in &r.quantities {
        let u = q.unit.as_deref();
        let v = |x: f64| with_unit(&six_digits(x), u);
        if crate::uq::method::notes_of_kind(&s.method.kind).adaptive {
            // An adaptive method: its runs are not samples of the inputs' law.
            print_reliability(q);
        } else if q.deterministic {
            println!(
                "  {} = {} ({}; {})",
                q.name,
                v(q.mean),
                if nominal { "nominal run" } else { "every run" },
                q.definition.text
            );
            if !nominal {
                // Every run gave the same value: still a count over the runs, as on the page.
                print_exceedances(q);
            } else {
                for e in &q.exceedance_counts {
                    let relation = if q.mean > e.limit {
                        "exceeds"
                    } else if q.mean == e.limit {
                        "equals"
                    } else {
                        "is below"
                    };
                    println!(
                        "  {} = {} {relation} the limit {} (nominal run; no probability)",
                        q.name,
                        v(q.mean),
                        with_unit(&e.limit.to_string(), u)
                    );
                }
            }
        } else {
            // As the report page writes them: to the resolution the spread allows.
            let spread = |x: f64| with_unit(&to_spread(x, q.std).replace('\u{202f}', ""), u);
            println!(
                "  {}: mean {}, Std {} ({}; {})",
                q.name,
                spread(q.mean),
                spread(q.std),
                count(q.n_valid, "valid run", "valid runs"),
                q.definition.text
            );
            if let Some(line) = split_line(q) {
                println!("{line}");
            }
            print_given_data_ranking(q);
            print_exceedances(q);
        }
    }
    if s.failed_runs > 0 {
        let points = if s.failed_runs == 1 {
            "point"
        } else {
            "points"
        };
        println!("{} {points} failed (see points.csv)", s.failed_runs);
    }
}

/// A nested quantity's variance split (as on the page and in summary.json):
/// `q: variance from the inner parameters (k1, k2) 62 % (95 % interval 55–70 %), from the
/// outer parameters (seed) 38 % (30–45 %); 16 outer samples`.
fn split_line(q: &ScalarStats) -> Option<String> {
    let n = q.nested.as_ref()?;
    let v = &n.variance_split;
    let pct = |x: f64| format!("{:.0} %", 100.0 * x);
    let names = |list: &[String]| match list.is_empty() {
        true => String::new(),
        false => format!(" ({})", list.join(", ")),
    };
    Some(format!(
        "  {}: variance from the inner parameters{} {} (95 % interval {}–{}), from the outer \
         parameters{} {} ({}–{}); {}",
        q.name,
        names(&n.conditional.inner_names),
        pct(v.inner),
        pct(v.inner_ci[0]),
        pct(v.inner_ci[1]),
        names(&n.conditional.outer_names),
        pct(v.outer),
        pct(v.outer_ci[0]),
        pct(v.outer_ci[1]),
        count(n.outer_samples, "outer sample", "outer samples")
    ))
}

/// One line of the most influential parameters of a quantity whose first-order indices were
/// estimated from the runs (`mc`, `lhs`, `qmc`):
/// `  Y: first-order indices from the runs: x2 0.44 [0.41, 0.47], x1 0.31 [...], x3 0.01 [...]`.
fn print_given_data_ranking(q: &ScalarStats) {
    let Some(s) = q.sobol.as_ref().filter(|s| s.estimator.is_some()) else {
        return;
    };
    let mut ranked: Vec<(&String, f64)> = s
        .first
        .iter()
        .filter(|(_, v)| v.is_finite())
        .map(|(n, v)| (n, *v))
        .collect();
    if ranked.is_empty() {
        return;
    }
    ranked.sort_by(|a, b| b.1.total_cmp(&a.1).then(a.0.cmp(b.0)));
    let top: Vec<String> = ranked
        .iter()
        .take(3)
        .map(|(n, v)| {
            let ci = s.first_ci.as_ref().and_then(|c| c.get(*n));
            match ci {
                Some([lo, hi]) => format!("{n} {} [{}, {}]", sig(*v), sig(*lo), sig(*hi)),
                None => format!("{n} {}", sig(*v)),
            }
        })
        .collect();
    let more = ranked.len().saturating_sub(3);
    let more = if more > 0 {
        format!(" (+{more} more)")
    } else {
        String::new()
    };
    println!(
        "  {}: first-order indices from the runs: {}{more}",
        q.name,
        top.join(", ")
    );
}

/// One line per probability of a reliability method
/// (`P(q > 12.3): 1.02e-4 (95 % interval 9.1e-5–1.14e-4, CoV 3.1 %), β = 3.72;
/// importance_sampling, 1 234 runs`), and Morris's ranking.
fn print_reliability(q: &ScalarStats) {
    let value = |x: f64| with_unit(&x.to_string(), q.unit.as_deref());
    for r in q.reliability.iter().flatten() {
        let op = if r.direction == "below" { "<" } else { ">" };
        let mut extra = Vec::new();
        if let Some([lo, hi]) = r.ci_95 {
            extra.push(format!("95 % interval {}–{}", sig(lo), sig(hi)));
        }
        if let Some(c) = r.cov_words() {
            extra.push(c);
        }
        if let Some(u) = r.upper_95 {
            extra.push(format!("95 % upper bound {}", sig(u)));
        }
        let extra = match extra.is_empty() {
            true => String::new(),
            false => format!(" ({})", extra.join(", ")),
        };
        let beta = r.beta.map_or(String::new(), |b| format!(", β = {b:.3}"));
        println!(
            "  P({} {op} {}): {}{extra}{beta}; {}, {}",
            q.name,
            value(r.limit),
            sig(r.p),
            r.method,
            count(r.runs, "run", "runs")
        );
    }
    if q.reliability.is_none() && q.morris.is_none() {
        println!(
            "  {}: no probability asked (values over the runs from {} to {})",
            q.name,
            value(q.min),
            value(q.max)
        );
    }
    if let Some(m) = &q.morris {
        let top: Vec<String> = m
            .ranking
            .iter()
            .take(8)
            .map(|n| format!("{n} {}", sig(m.mu_star[n])))
            .collect();
        println!(
            "  {}: Morris μ* (per unit of probability level), largest first: {}{}",
            q.name,
            top.join(", "),
            if m.ranking.len() > 8 { ", …" } else { "" }
        );
    }
}

/// `P(W > 2.5): 75 of 5 000 runs exceeded 2.5: P = 0.015 (95 % interval …)` for each limit
/// of a quantity (`P(W < 1)` for its limits below), the limit with its unit.
fn print_exceedances(q: &ScalarStats) {
    for e in &q.exceedance_counts {
        let value = |x: f64| with_unit(&x.to_string(), q.unit.as_deref());
        println!(
            "  P({} {} {}): {}",
            q.name,
            if e.is_below() { "<" } else { ">" },
            value(e.limit),
            e.describe_with(&value)
        );
    }
}

/// The result of `run` for a suite: one line per variant.
pub(crate) fn print_suite(r: &SuiteResult, out: &Path) {
    for v in &r.variants {
        for w in v.summary.warnings.iter().skip(v.warnings_shown) {
            eprintln!("uq-driver: warning: {}: {w}", v.summary.study);
        }
    }
    println!(
        "{}: report {}",
        r.summary.suite,
        out.join("index.html").display()
    );
    for v in &r.summary.variants {
        println!(
            "  {:<12} {:<16} {:>7} {}, wall time {:.2} s",
            v.name,
            v.method,
            v.model_runs,
            if v.model_runs == 1 {
                "model run"
            } else {
                "model runs"
            },
            v.wall_time_s
        );
    }
}

/// `x` with six significant digits: fixed-point from 1e-3 to 1e6 (trailing zeros kept, as
/// `{:.6}` did for values near 1), exponent notation outside (a quantity of 1e-9 no longer
/// prints as 0.000000).
fn six_digits(x: f64) -> String {
    let a = x.abs();
    if x == 0.0 || !x.is_finite() {
        format!("{x}")
    } else if (1e-3..1e6).contains(&a) {
        let decimals = (5 - a.log10().floor() as i32).max(0) as usize;
        format!("{x:.decimals$}")
    } else {
        format!("{x:.5e}")
    }
}

#[cfg(test)]
mod tests {
    use super::six_digits;

    #[test]
    fn a_tiny_quantity_is_not_printed_as_zero() {
        assert_eq!(six_digits(1.234567e-9), "1.23457e-9");
        assert_eq!(six_digits(0.5), "0.500000");
        assert_eq!(six_digits(-4.5678912), "-4.56789");
        assert_eq!(six_digits(123.456789), "123.457");
        assert_eq!(six_digits(2.5e7), "2.50000e7");
        assert_eq!(six_digits(0.0), "0");
    }
}
