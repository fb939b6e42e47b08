//! What the values of a finished run must be: finite series, and per scalar quantity a valid
//! (value, code) pair. A run never stores anything else (a non-finite output fails its
//! point), so a stored record that breaks these rules was damaged or edited: opening the
//! store makes its point failed, with a message that says so, instead of analysing it (a NaN
//! would make every statistic of its columns NaN).

use crate::qoi::evaluate::Code;

/// The layout of a record and what each value must be.
#[derive(Clone, Debug, Default)]
pub(crate) struct RecordRules {
    /// The stored series, in record order (each `times.len()` values).
    series: Vec<String>,
    /// The communication points (s).
    times: Vec<f64>,
    /// The scalar quantities, in record order (each a value and a code).
    quantities: Vec<String>,
}

impl RecordRules {
    /// The rules of records of `series` over `times` (s), then `quantities`.
    pub(crate) fn new(series: &[String], times: &[f64], quantities: Vec<String>) -> RecordRules {
        RecordRules {
            series: series.to_vec(),
            times: times.to_vec(),
            quantities,
        }
    }

    /// What is wrong with `values` (a successful run's record), if anything: "a non-finite
    /// value (NaN) of output 'q' at t = 0.5 s".
    pub(crate) fn check(&self, values: impl Iterator<Item = f64>) -> Result<(), String> {
        let nt = self.times.len();
        let n_series = self.series.len() * nt;
        let mut pair = [0.0; 2];
        for (k, v) in values.enumerate() {
            if k < n_series {
                if !v.is_finite() {
                    return Err(format!(
                        "a non-finite value ({v}) of output '{}' at t = {} s",
                        self.series[k / nt],
                        self.times[k % nt]
                    ));
                }
                continue;
            }
            let j = k - n_series;
            pair[j % 2] = v;
            if j.is_multiple_of(2) {
                continue;
            }
            let Some(name) = self.quantities.get(j / 2) else {
                break;
            };
            let [value, code] = pair;
            let ok = f64::from(Code::Ok as u8);
            let known = [Code::Ok, Code::NeverHunts, Code::NeverStops];
            if !known.iter().any(|&c| f64::from(c as u8) == code) {
                return Err(format!("an invalid code ({code}) of quantity '{name}'"));
            }
            if code == ok && !value.is_finite() {
                return Err(format!("a non-finite value ({value}) of quantity '{name}'"));
            }
        }
        Ok(())
    }

    /// [`RecordRules::check`] of a record's values as stored (little-endian f64).
    pub(crate) fn check_bytes(&self, payload: &[u8]) -> Result<(), String> {
        self.check(
            payload
                .chunks_exact(8)
                .map(|c| f64::from_le_bytes(c.try_into().unwrap_or([0; 8]))),
        )
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn non_finite_series_values_and_invalid_quantity_pairs_are_named() {
        let r = RecordRules::new(&["q".into(), "v".into()], &[0.0, 0.5], vec!["W".into()]);
        assert_eq!(r.check([1.0, 2.0, 3.0, 4.0, 2.5, 0.0].into_iter()), Ok(()));
        // NaN value with a code that says there is no value: as a run stores it.
        assert_eq!(
            r.check([1.0, 2.0, 3.0, 4.0, f64::NAN, 1.0].into_iter()),
            Ok(())
        );
        assert_eq!(
            r.check([1.0, 2.0, 3.0, f64::NAN, 2.5, 0.0].into_iter()),
            Err("a non-finite value (NaN) of output 'v' at t = 0.5 s".into())
        );
        assert_eq!(
            r.check([1.0, f64::INFINITY, 3.0, 4.0, 2.5, 0.0].into_iter()),
            Err("a non-finite value (inf) of output 'q' at t = 0.5 s".into())
        );
        assert_eq!(
            r.check([1.0, 2.0, 3.0, 4.0, f64::NAN, 0.0].into_iter()),
            Err("a non-finite value (NaN) of quantity 'W'".into())
        );
        assert_eq!(
            r.check([1.0, 2.0, 3.0, 4.0, 1.0, 7.0].into_iter()),
            Err("an invalid code (7) of quantity 'W'".into())
        );
        let bytes: Vec<u8> = [1.0f64, 2.0, 3.0, f64::NAN, 2.5, 0.0]
            .iter()
            .flat_map(|x| x.to_le_bytes())
            .collect();
        assert!(r.check_bytes(&bytes).is_err());
    }
}
