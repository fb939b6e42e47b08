//! The random inputs of a study as a person reads them: the distribution by name with the
//! numbers a study file gives (mean and Std or CoV, bounds), its mean, Std and CoV, and its
//! support, instead of the parameters of the implementation (e.g. the lognormal's μ and σ
//! of ln X, shown beside).

use crate::results::numbers::{as_written, computed, written as num};
use crate::uq::distributions::RandomParameter;
use crate::uq::random_inputs::Correlation;

/// One row of the inputs table: `[parameter, unit, distribution as written, mean, Std, CoV,
/// support]`. Mean and Std read as a study file writes them, in one notation (`182300` and
/// `18230`, or `1.773e6` and `1.773e5`).
pub fn row(p: &RandomParameter, unit: Option<&str>) -> Vec<String> {
    let d = &p.distribution;
    let (mean, std) = (d.mean(), d.std());
    let cov = if mean != 0.0 {
        format!("{} %", computed(&[100.0 * std / mean.abs()])[0])
    } else {
        "–".into()
    };
    let (lo, hi) = d.support();
    // The mean and Std of a normal or lognormal are the numbers written (up to round-off);
    // those of other kinds are computed.
    let kind = serde_json::to_value(d)
        .ok()
        .and_then(|j| j.get("kind").and_then(|k| k.as_str()).map(str::to_owned));
    let ms = match kind.as_deref() {
        Some("normal" | "log_normal") => as_written(&[mean, std]),
        _ => computed(&[mean, std]),
    };
    let bounds = as_written(&[lo, hi]);
    vec![
        p.name.clone(),
        unit.unwrap_or("").to_owned(),
        written(p),
        ms[0].clone(),
        ms[1].clone(),
        cov,
        format!("{} … {}", bounds[0], bounds[1]),
    ]
}

/// The header of [`row`].
pub fn header() -> Vec<String> {
    [
        "parameter",
        "unit",
        "distribution (as in the study file)",
        "mean",
        "Std",
        "CoV",
        "support",
    ]
    .iter()
    .map(|s| s.to_string())
    .collect()
}

/// One row of the inputs table of a nominal study, which ran once with every parameter at
/// its nominal value: `[parameter, unit, value used, distribution (not sampled)]`.
pub fn nominal_row(p: &RandomParameter, unit: Option<&str>) -> Vec<String> {
    vec![
        p.name.clone(),
        unit.unwrap_or("").to_owned(),
        num(p.distribution.nominal()),
        format!("{} (not sampled)", written(p)),
    ]
}

/// The header of [`nominal_row`].
pub fn nominal_header() -> Vec<String> {
    [
        "parameter",
        "unit",
        "value used",
        "distribution in the study file",
    ]
    .iter()
    .map(|s| s.to_string())
    .collect()
}

/// The distribution in the terms of a study file, e.g. `normal, mean 100, std 10 (cov 0.1)`,
/// `lognormal, mean 100, std 10 (cov 0.1) (ln X ~ N(4.6002, 0.099751²))`,
/// `uniform, low 1, high 2`; each number the shortest text that reads back as it, mean and
/// Std in one notation. Kinds this function does not know are listed with their fields.
pub fn written(p: &RandomParameter) -> String {
    let d = &p.distribution;
    let json = serde_json::to_value(d).unwrap_or_default();
    let field = |k: &str| json.get(k).and_then(serde_json::Value::as_f64);
    let kind = json.get("kind").and_then(|k| k.as_str()).unwrap_or("?");
    let moments = |mean: f64, std: f64| {
        let ms = as_written(&[mean, std]);
        if mean != 0.0 {
            format!(
                "mean {}, std {} (cov {})",
                ms[0],
                ms[1],
                computed(&[std / mean.abs()])[0]
            )
        } else {
            format!("mean {}, std {}", ms[0], ms[1])
        }
    };
    // The lognormal's parameters are computed: five significant digits say enough.
    let five = |x: f64| computed(&[format!("{x:.4e}").parse().unwrap_or(x)]).swap_remove(0);
    match kind {
        "normal" => format!("normal, {}", moments(d.mean(), d.std())),
        "log_normal" => format!(
            "lognormal, {} (ln X ~ N({}, {}²))",
            moments(d.mean(), d.std()),
            five(field("mu").unwrap_or(f64::NAN)),
            five(field("sigma").unwrap_or(f64::NAN)),
        ),
        "uniform" => {
            let b = as_written(&[
                field("low").unwrap_or(f64::NAN),
                field("high").unwrap_or(f64::NAN),
            ]);
            format!("uniform, low {}, high {}", b[0], b[1])
        }
        "truncated_normal" => {
            let (m, s) = (
                field("mean").unwrap_or(f64::NAN),
                field("std").unwrap_or(f64::NAN),
            );
            let (lo, hi) = d.support();
            let b = as_written(&[lo, hi]);
            format!(
                "truncated_normal, {}, low {}, high {} (of the normal before truncation)",
                moments(m, s),
                b[0],
                b[1]
            )
        }
        other => {
            let fields: Vec<String> = json
                .as_object()
                .into_iter()
                .flatten()
                .filter(|(k, _)| k.as_str() != "kind")
                .map(|(k, v)| match v.as_f64() {
                    Some(x) => format!("{k} {}", num(x)),
                    None => format!("{k} {v}"),
                })
                .collect();
            format!("{other}, {}", fields.join(", "))
        }
    }
}

/// The correlation matrix of the correlated inputs (`[[correlation]]`), as a header and rows:
/// each cell the requested Pearson correlation of the two inputs' values (0 for a pair not
/// given, 1 on the diagonal), and in brackets the correlation of their normal scores that the
/// Gaussian copula (Nataf transformation) uses to give it. `None` for independent inputs.
pub fn correlation_table(
    c: &Correlation,
    parameters: &[RandomParameter],
) -> Option<(Vec<String>, Vec<Vec<String>>)> {
    let shown: Vec<usize> = (0..parameters.len())
        .filter(|&i| c.correlated.get(i).copied().unwrap_or(false))
        .collect();
    let shown = if shown.is_empty() {
        // Read back from summary.json (no flags): every input named by a pair.
        (0..parameters.len())
            .filter(|&i| {
                c.pairs
                    .iter()
                    .any(|p| p.between.contains(&parameters[i].name))
            })
            .collect()
    } else {
        shown
    };
    if shown.is_empty() {
        return None;
    }
    let requested = |a: &str, b: &str| -> f64 {
        if a == b {
            return 1.0;
        }
        c.pairs
            .iter()
            .find(|p| {
                (p.between[0] == a && p.between[1] == b) || (p.between[0] == b && p.between[1] == a)
            })
            .map_or(0.0, |p| p.rho)
    };
    let z = &c.normal_correlation;
    let mut header = vec![String::new()];
    header.extend(shown.iter().map(|&i| parameters[i].name.clone()));
    let rows = shown
        .iter()
        .map(|&i| {
            let mut row = vec![parameters[i].name.clone()];
            row.extend(shown.iter().map(|&j| {
                let rho = requested(&parameters[i].name, &parameters[j].name);
                match (i == j, z.get((i, j))) {
                    (false, Some(&rz)) if rho != 0.0 || rz != 0.0 => {
                        format!("{} [{}]", num(rho), computed(&[rz])[0])
                    }
                    _ => num(rho),
                }
            }));
            row
        })
        .collect();
    Some((header, rows))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::uq::Distribution;

    fn param(d: Distribution) -> RandomParameter {
        RandomParameter {
            name: "K".into(),
            distribution: d,
        }
    }

    #[test]
    fn inputs_read_as_written() {
        let n = param(Distribution::normal(100.0, 10.0).unwrap());
        assert_eq!(written(&n), "normal, mean 100, std 10 (cov 0.1)");
        let r = row(&n, Some("N/m"));
        assert_eq!(r[1], "N/m");
        assert_eq!(r[5], "10 %");
        assert_eq!(r[6], "−∞ … ∞");
        let l = param(Distribution::lognormal_from_mean_std(100.0, 10.0).unwrap());
        let text = written(&l);
        assert!(
            text.starts_with("lognormal, mean 100, std 10 (cov 0.1)"),
            "{text}"
        );
        assert!(text.contains("ln X ~ N(4.6002, 0.099751²)"), "{text}");
        assert!(!text.contains("LogNormal {"), "{text}");
        let u = param(Distribution::uniform(1.0, 2.0).unwrap());
        assert_eq!(written(&u), "uniform, low 1, high 2");
        assert_eq!(row(&u, None)[6], "1 … 2");
        let t = param(Distribution::truncated_normal(1.0, 0.5, 0.0, f64::INFINITY).unwrap());
        assert!(written(&t).contains("low 0, high ∞"), "{}", written(&t));
    }

    #[test]
    fn inputs_keep_the_digits_the_study_file_wrote() {
        // `mean = 0.1823e6, cov = 0.1` was shown as "mean 1.82e5, std 18230"
        // (a digit dropped, two notations in one row).
        let k = param(Distribution::normal(0.1823e6, 0.1 * 0.1823e6).unwrap());
        assert_eq!(written(&k), "normal, mean 182300, std 18230 (cov 0.1)");
        let r = row(&k, None);
        assert_eq!((r[3].as_str(), r[4].as_str()), ("182300", "18230"));
        let k = param(Distribution::normal(1773000.0, 177300.0).unwrap());
        assert_eq!(written(&k), "normal, mean 1.773e6, std 1.773e5 (cov 0.1)");
        let r = row(&k, None);
        assert_eq!((r[3].as_str(), r[4].as_str()), ("1.773e6", "1.773e5"));
        // A nominal study shows the value it used, and the distribution as not sampled.
        let r = nominal_row(&k, Some("N/m"));
        assert_eq!(r[2], "1.773e6");
        assert!(r[3].ends_with("(not sampled)"), "{}", r[3]);
    }

    /// The correlations (Nataf) the study declared were not shown on the page.
    #[test]
    fn the_page_shows_the_declared_correlations() {
        use crate::uq::random_inputs::CorrelationPair;
        let params: Vec<RandomParameter> = ["a", "b", "c"]
            .iter()
            .map(|n| RandomParameter {
                name: n.to_string(),
                distribution: Distribution::lognormal_from_mean_std(1.0, 0.5).unwrap(),
            })
            .collect();
        let pairs = vec![CorrelationPair {
            between: ["c".into(), "a".into()],
            rho: 0.5,
        }];
        let c = Correlation::new(&params, pairs).unwrap().unwrap();
        let (header, rows) = correlation_table(&c, &params).unwrap();
        assert_eq!(header, ["", "a", "c"]);
        assert_eq!(rows[0][0], "a");
        assert_eq!(rows[0][1], "1");
        assert_eq!(rows[1][1], rows[0][2]);
        // Lognormals: the normal scores need a correlation a little above 0.5.
        let rz = c.normal_correlation[(0, 2)];
        assert!(rz > 0.5 && rz < 0.6, "{rz}");
        assert!(rows[0][2].starts_with("0.5 ["), "{}", rows[0][2]);
    }
}
