//! The random inputs of a study as a person reads them: the distribution by name with the
//! numbers a study file gives (mean and Std or CoV, bounds), its mean, Std and CoV, and its
//! support, instead of the parameters of the implementation (e.g. the lognormal's μ and σ
//! of ln X, shown beside).

use crate::results::sig;
use crate::uq::distributions::RandomParameter;

/// One row of the inputs table: `[parameter, unit, distribution as written, mean, Std, CoV,
/// support]`.
pub fn row(p: &RandomParameter, unit: Option<&str>) -> Vec<String> {
    let d = &p.distribution;
    let (mean, std) = (d.mean(), d.std());
    let cov = if mean != 0.0 {
        format!("{} %", sig(100.0 * std / mean.abs()))
    } else {
        "–".into()
    };
    let (lo, hi) = d.support();
    vec![
        p.name.clone(),
        unit.unwrap_or("").to_owned(),
        written(p),
        sig(mean),
        sig(std),
        cov,
        format!("{} … {}", bound(lo), bound(hi)),
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

fn bound(x: f64) -> String {
    if x == f64::INFINITY {
        "∞".into()
    } else if x == f64::NEG_INFINITY {
        "−∞".into()
    } else {
        sig(x)
    }
}

/// The distribution in the terms of a study file, e.g. `normal, mean 100, std 10`,
/// `lognormal, mean 100, cov 0.1 (ln X ~ N(4.6, 0.0998²))`, `uniform, low 1, high 2`.
/// Kinds this function does not know are listed with their fields.
pub fn written(p: &RandomParameter) -> String {
    let d = &p.distribution;
    let json = serde_json::to_value(d).unwrap_or_default();
    let field = |k: &str| json.get(k).and_then(serde_json::Value::as_f64);
    let kind = json.get("kind").and_then(|k| k.as_str()).unwrap_or("?");
    let spread = |mean: f64, std: f64| {
        if mean != 0.0 {
            format!("std {} (cov {})", sig(std), sig(std / mean.abs()))
        } else {
            format!("std {}", sig(std))
        }
    };
    match kind {
        "normal" => format!(
            "normal, mean {}, {}",
            sig(d.mean()),
            spread(d.mean(), d.std())
        ),
        "log_normal" => format!(
            "lognormal, mean {}, {} (ln X ~ N({}, {}²))",
            sig(d.mean()),
            spread(d.mean(), d.std()),
            sig(field("mu").unwrap_or(f64::NAN)),
            sig(field("sigma").unwrap_or(f64::NAN)),
        ),
        "uniform" => format!(
            "uniform, low {}, high {}",
            sig(field("low").unwrap_or(f64::NAN)),
            sig(field("high").unwrap_or(f64::NAN))
        ),
        "truncated_normal" => {
            let (m, s) = (
                field("mean").unwrap_or(f64::NAN),
                field("std").unwrap_or(f64::NAN),
            );
            let (lo, hi) = d.support();
            format!(
                "truncated_normal, mean {}, {}, low {}, high {} (of the normal before truncation)",
                sig(m),
                spread(m, s),
                bound(lo),
                bound(hi)
            )
        }
        other => {
            let fields: Vec<String> = json
                .as_object()
                .into_iter()
                .flatten()
                .filter(|(k, _)| k.as_str() != "kind")
                .map(|(k, v)| match v.as_f64() {
                    Some(x) => format!("{k} {}", sig(x)),
                    None => format!("{k} {v}"),
                })
                .collect();
            format!("{other}, {}", fields.join(", "))
        }
    }
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
        assert_eq!(written(&n), "normal, mean 100, std 10.0 (cov 0.100)");
        let r = row(&n, Some("N/m"));
        assert_eq!(r[1], "N/m");
        assert_eq!(r[5], "10.0 %");
        assert_eq!(r[6], "−∞ … ∞");
        let l = param(Distribution::lognormal_from_mean_std(100.0, 10.0).unwrap());
        let text = written(&l);
        assert!(
            text.starts_with("lognormal, mean 100, std 10.0 (cov 0.100)"),
            "{text}"
        );
        assert!(text.contains("ln X ~ N(4.60"), "{text}");
        assert!(!text.contains("LogNormal {"), "{text}");
        let u = param(Distribution::uniform(1.0, 2.0).unwrap());
        assert_eq!(written(&u), "uniform, low 1.00, high 2.00");
        assert_eq!(row(&u, None)[6], "1.00 … 2.00");
        let t = param(Distribution::truncated_normal(1.0, 0.5, 0.0, f64::INFINITY).unwrap());
        assert!(written(&t).contains("low 0, high ∞"), "{}", written(&t));
    }
}
