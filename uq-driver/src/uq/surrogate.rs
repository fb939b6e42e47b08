//! The exported chaos surrogate of a study (`DIR/surrogate.json`): the inputs and their maps,
//! the correlation, and for every output (per time) and scalar quantity the multi-indices,
//! the coefficients and the estimated truncation error. [`Surrogate`] reads it back,
//! evaluates it at physical parameter values and samples it.
//!
//! The format (version 1) is documented in the user guide
//! (`docs/src/reference/surrogate-format.md`). A chaos term is `prod_i p^(i)_{k_i}(t_i)`,
//! `p^(i)` the orthonormal polynomial of input `i`'s family on its germ `t_i`; an input's
//! value is `offset + scale t_i` (`map = "affine"`) or `F_i^-1(Phi(t_i))` (`map =
//! "normal"`), correlated inputs through the Gaussian copula.

use std::path::Path;

use nalgebra::DMatrix;
use serde::{Deserialize, Serialize};

use crate::text::csv::{push_shortest, shortest};
use crate::uq::distributions::{Distribution, Germ, RandomParameter};
use crate::uq::method::ChaosError;
use crate::uq::pce::{germ_draw, germ_draws, Basis, Family, MultiIndexSet, Pce};
use crate::uq::random_inputs::{Correlation, CorrelationPair, RandomInputs};

/// `format` of the file.
pub const FORMAT: &str = "railuq-surrogate";
/// `version` of the file.
pub const VERSION: u32 = 1;

/// Errors of reading and using a surrogate.
#[derive(Debug, thiserror::Error)]
pub enum SurrogateError {
    /// The file cannot be read.
    #[error("{path}: {source}")]
    Io {
        /// The file.
        path: String,
        /// Why.
        source: std::io::Error,
    },
    /// Not a surrogate file of a known version, or inconsistent.
    #[error("{0}")]
    Invalid(String),
    /// A parameter given that the surrogate does not have, or a bad value.
    #[error("{0}")]
    Input(String),
}

/// How an input's value follows from its germ coordinate.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(tag = "map", rename_all = "snake_case")]
pub enum InputMap {
    /// `x = offset + scale · t`.
    Affine {
        /// Offset (units of the input).
        offset: f64,
        /// Scale (units of the input).
        scale: f64,
    },
    /// `x = F^-1(Phi(t))`, `t` standard normal.
    Normal,
}

/// An input of the surrogate.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct SurrogateInput {
    /// FMU variable name.
    pub name: String,
    /// Its distribution.
    pub distribution: Distribution,
    /// The orthonormal family of its germ (`{"family": "hermite"}`, ...).
    pub family: Family,
    /// How the germ maps to the input (before the copula, for a correlated input).
    #[serde(flatten)]
    pub map: InputMap,
}

/// The correlation of the inputs.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct SurrogateCorrelation {
    /// The requested pairs (Pearson correlation of the physical values).
    pub pairs: Vec<CorrelationPair>,
    /// The normal-space correlation matrix of the Gaussian copula (study order).
    pub normal_correlation: Vec<Vec<f64>>,
}

/// A truncation-error estimate.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct ErrorEstimate {
    /// `loo`, `level_difference` or `order_difference`.
    pub kind: String,
    /// Per output time (outputs) or one value (quantities).
    pub values: Vec<f64>,
}

impl From<&ChaosError> for ErrorEstimate {
    fn from(e: &ChaosError) -> Self {
        ErrorEstimate {
            kind: e.kind.name().to_owned(),
            values: e.values.clone(),
        }
    }
}

/// The chaos of an output over time, or of a scalar quantity (one "time").
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct SurrogateChaos {
    /// Output or quantity name.
    pub name: String,
    /// Communication points (s); absent for a scalar quantity.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub times: Option<Vec<f64>>,
    /// The multi-indices `k` (one entry per input).
    pub multi_indices: Vec<Vec<usize>>,
    /// Coefficients: per time (one for a quantity), one per multi-index.
    pub coefficients: Vec<Vec<f64>>,
    /// The estimated relative truncation error, if the method gives one.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub error: Option<ErrorEstimate>,
}

/// `surrogate.json`.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct SurrogateFile {
    /// Always `railuq-surrogate`.
    pub format: String,
    /// Format version (1).
    pub version: u32,
    /// Study name.
    pub study: String,
    /// Method kind.
    pub method: String,
    /// The standard space: `normal` (every input through the normal map) or `askey`.
    pub germ: Germ,
    /// The inputs, in study order.
    pub inputs: Vec<SurrogateInput>,
    /// The correlation, if the inputs are correlated.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub correlation: Option<SurrogateCorrelation>,
    /// Outputs over time.
    pub outputs: Vec<SurrogateChaos>,
    /// Scalar quantities.
    pub quantities: Vec<SurrogateChaos>,
}

/// A named chaos of a study, with its error estimate.
#[derive(Clone, Debug)]
pub struct NamedChaos {
    /// Output or quantity name.
    pub name: String,
    /// Times (outputs) or `None` (quantities).
    pub times: Option<Vec<f64>>,
    /// The chaos (one column per time, or one).
    pub pce: Pce,
    /// Its error estimate.
    pub error: Option<ChaosError>,
}

impl SurrogateFile {
    /// The file of a study's chaoses: `germ` and `inputs` those of the design.
    pub fn new(
        study: &str,
        method: &str,
        germ: Germ,
        inputs: &RandomInputs,
        outputs: &[NamedChaos],
        quantities: &[NamedChaos],
    ) -> SurrogateFile {
        let inputs_out = inputs
            .iter()
            .map(|p| {
                let d = &p.distribution;
                let (family, map) = chaos_input(germ, d);
                SurrogateInput {
                    name: p.name.clone(),
                    distribution: d.clone(),
                    family,
                    map,
                }
            })
            .collect();
        let chaos = |c: &NamedChaos| SurrogateChaos {
            name: c.name.clone(),
            times: c.times.clone(),
            multi_indices: c.pce.set().indices().to_vec(),
            coefficients: (0..c.pce.outputs())
                .map(|k| c.pce.coeffs.column(k).iter().copied().collect())
                .collect(),
            error: c.error.as_ref().map(ErrorEstimate::from),
        };
        SurrogateFile {
            format: FORMAT.into(),
            version: VERSION,
            study: study.into(),
            method: method.into(),
            germ,
            inputs: inputs_out,
            correlation: inputs.correlation.as_ref().map(|c| SurrogateCorrelation {
                pairs: c.pairs.clone(),
                normal_correlation: c
                    .normal_correlation
                    .row_iter()
                    .map(|r| r.iter().copied().collect())
                    .collect(),
            }),
            outputs: outputs.iter().map(chaos).collect(),
            quantities: quantities.iter().map(chaos).collect(),
        }
    }
}

/// The family of an input's chaos and how its germ maps to it, with the standard space
/// `germ` (what the evaluation uses: [`RandomInputs::to_germ`]).
fn chaos_input(germ: Germ, d: &Distribution) -> (Family, InputMap) {
    match (germ, Family::of(d), d.askey_affine()) {
        (Germ::Askey, Some(f), Some((offset, scale))) => (f, InputMap::Affine { offset, scale }),
        (_, _, _) => match *d {
            Distribution::Normal { mean, std } => (
                Family::Hermite,
                InputMap::Affine {
                    offset: mean,
                    scale: std,
                },
            ),
            _ => (Family::Hermite, InputMap::Normal),
        },
    }
}

/// The highest polynomial degree a surrogate may have in one input: far above any chaos a
/// study fits, low enough that evaluating it stays cheap (a damaged index is refused instead
/// of allocating for it).
pub const MAX_DEGREE: usize = 1000;

/// `value` as `surrogate.json` spells it (`"askey"`, `{"family":"legendre"}`).
fn json(value: &impl Serialize) -> String {
    serde_json::to_string(value).unwrap_or_default()
}

/// An input's family and map as the file spells them, one object:
/// `{"family":"hermite","map":"affine","offset":100.0,"scale":10.0}`.
fn as_in_file(family: &Family, map: &InputMap) -> String {
    let mut v = serde_json::to_value(family).unwrap_or_default();
    if let (Some(o), Ok(serde_json::Value::Object(m))) =
        (v.as_object_mut(), serde_json::to_value(map))
    {
        o.extend(m);
    }
    v.to_string()
}

/// Checks what [`Surrogate::new`] relies on beyond the format: a chaos germ, each input's
/// family and map those of its distribution, sane multi-indices, and finite coefficients of
/// the right count (one vector per time of an output, one for a quantity).
fn validate(f: &SurrogateFile) -> Result<(), String> {
    if f.germ == Germ::Uniform {
        return Err("germ \"uniform\" is not a chaos germ (\"normal\" or \"askey\")".into());
    }
    for (i, input) in f.inputs.iter().enumerate() {
        if f.inputs[..i].iter().any(|o| o.name == input.name) {
            return Err(format!("input '{}' is listed twice", input.name));
        }
        let (family, map) = chaos_input(f.germ, &input.distribution);
        let close = |a: f64, b: f64| (a - b).abs() <= 1e-12 * a.abs().max(b.abs()).max(1.0);
        let same_map = match (&map, &input.map) {
            (InputMap::Normal, InputMap::Normal) => true,
            (
                InputMap::Affine { offset, scale },
                InputMap::Affine {
                    offset: o,
                    scale: s,
                },
            ) => close(*offset, *o) && close(*scale, *s),
            _ => false,
        };
        if family != input.family || !same_map {
            return Err(format!(
                "input '{}': {} does not match its distribution under germ {} (expected {})",
                input.name,
                as_in_file(&input.family, &input.map),
                json(&f.germ),
                as_in_file(&family, &map),
            ));
        }
    }
    for (c, is_output) in f
        .outputs
        .iter()
        .map(|c| (c, true))
        .chain(f.quantities.iter().map(|c| (c, false)))
    {
        let name = &c.name;
        if c.multi_indices.is_empty() {
            return Err(format!("'{name}': no multi-index"));
        }
        if let Some(k) = c
            .multi_indices
            .iter()
            .find(|k| k.iter().any(|&d| d > MAX_DEGREE))
        {
            return Err(format!(
                "'{name}': multi-index {k:?} has a degree above {MAX_DEGREE}"
            ));
        }
        let wanted = match (is_output, &c.times) {
            (true, Some(t)) if !t.is_empty() => {
                if t.iter().any(|x| !x.is_finite()) || t.windows(2).any(|w| w[1] < w[0]) {
                    return Err(format!("'{name}': the times must be finite and increasing"));
                }
                t.len()
            }
            (true, _) => return Err(format!("'{name}': an output needs its times")),
            (false, _) => 1,
        };
        if c.coefficients.len() != wanted {
            return Err(format!(
                "'{name}': {} coefficient vectors for {wanted} {}",
                c.coefficients.len(),
                if is_output {
                    "times"
                } else {
                    "value (a quantity has one)"
                }
            ));
        }
        if c.coefficients.iter().flatten().any(|v| !v.is_finite()) {
            return Err(format!("'{name}': a coefficient is not a finite number"));
        }
    }
    Ok(())
}

/// A surrogate ready to evaluate: the inputs with their copula, and the chaoses.
#[derive(Clone, Debug)]
pub struct Surrogate {
    /// The file it was read from.
    pub file: SurrogateFile,
    /// The inputs (marginals and copula).
    pub inputs: RandomInputs,
    /// One chaos per output (columns: times), then one per quantity (one column).
    chaos: Vec<Pce>,
}

/// Values of a surrogate at one point.
#[derive(Clone, Debug, PartialEq)]
pub struct SurrogateValues {
    /// Per output: the values at its times.
    pub outputs: Vec<Vec<f64>>,
    /// Per quantity.
    pub quantities: Vec<f64>,
}

impl Surrogate {
    /// Reads `DIR/surrogate.json` (or the file itself when `path` is a file).
    pub fn load(path: &Path) -> Result<Surrogate, SurrogateError> {
        let file = if path.is_dir() {
            path.join("surrogate.json")
        } else {
            path.to_path_buf()
        };
        let text = std::fs::read_to_string(&file).map_err(|source| SurrogateError::Io {
            path: file.display().to_string(),
            source,
        })?;
        let f: SurrogateFile = serde_json::from_str(&text).map_err(|e| {
            SurrogateError::Invalid(format!("{}: not a surrogate file: {e}", file.display()))
        })?;
        Surrogate::new(f)
    }

    /// Checks a parsed file and prepares it for evaluation.
    pub fn new(f: SurrogateFile) -> Result<Surrogate, SurrogateError> {
        let invalid = |m: String| SurrogateError::Invalid(m);
        if f.format != FORMAT || f.version != VERSION {
            return Err(invalid(format!(
                "format {} version {} is not {FORMAT} version {VERSION}",
                f.format, f.version
            )));
        }
        validate(&f).map_err(invalid)?;
        let parameters: Vec<RandomParameter> = f
            .inputs
            .iter()
            .map(|i| {
                i.distribution
                    .validate()
                    .map_err(|e| invalid(format!("input '{}': {e}", i.name)))?;
                Ok(RandomParameter::new(i.name.clone(), i.distribution.clone()))
            })
            .collect::<Result<_, SurrogateError>>()?;
        let pairs = f
            .correlation
            .as_ref()
            .map_or(Vec::new(), |c| c.pairs.clone());
        let correlation =
            Correlation::new(&parameters, pairs).map_err(|e| invalid(e.to_string()))?;
        let inputs = RandomInputs {
            parameters,
            correlation,
        };
        let families: Vec<Family> = f.inputs.iter().map(|i| i.family).collect();
        let chaos = f
            .outputs
            .iter()
            .chain(&f.quantities)
            .map(|c| {
                let set = MultiIndexSet::from_indices(families.len(), c.multi_indices.clone())
                    .map_err(|e| invalid(format!("'{}': {e}", c.name)))?;
                let basis = Basis::new(families.clone(), set)
                    .map_err(|e| invalid(format!("'{}': {e}", c.name)))?;
                let rows = basis.len();
                if c.coefficients.iter().any(|col| col.len() != rows) {
                    return Err(invalid(format!(
                        "'{}': every coefficient vector needs {rows} entries",
                        c.name
                    )));
                }
                let coeffs =
                    DMatrix::from_fn(rows, c.coefficients.len(), |r, k| c.coefficients[k][r]);
                Pce::new(basis, coeffs).map_err(|e| invalid(e.to_string()))
            })
            .collect::<Result<_, _>>()?;
        Ok(Surrogate {
            file: f,
            inputs,
            chaos,
        })
    }

    /// The physical values of every input from `NAME=VALUE` assignments; inputs not given
    /// take their nominal value (the mean).
    pub fn point(&self, at: &[(String, f64)]) -> Result<Vec<f64>, SurrogateError> {
        let mut x: Vec<f64> = self
            .inputs
            .iter()
            .map(|p| p.distribution.nominal())
            .collect();
        for (k, (name, v)) in at.iter().enumerate() {
            if at[..k].iter().any(|(n, _)| n == name) {
                return Err(SurrogateError::Input(format!(
                    "'{name}' is given more than once"
                )));
            }
            let i = self
                .inputs
                .iter()
                .position(|p| &p.name == name)
                .ok_or_else(|| {
                    SurrogateError::Input(format!(
                        "'{name}' is not an input of the surrogate (inputs: {})",
                        self.inputs
                            .iter()
                            .map(|p| p.name.as_str())
                            .collect::<Vec<_>>()
                            .join(", ")
                    ))
                })?;
            let (lo, hi) = self.inputs[i].distribution.support();
            if !v.is_finite() || *v < lo || *v > hi {
                return Err(SurrogateError::Input(format!(
                    "{name} = {v} is outside the support [{lo}, {hi}] of its distribution"
                )));
            }
            x[i] = *v;
        }
        Ok(x)
    }

    /// Every output and quantity at the physical values `x` (one per input).
    pub fn eval(&self, x: &[f64]) -> SurrogateValues {
        let t = self.inputs.to_germ(self.file.germ, x);
        self.eval_germ(&t)
    }

    fn eval_germ(&self, t: &[f64]) -> SurrogateValues {
        let n_out = self.file.outputs.len();
        SurrogateValues {
            outputs: self.chaos[..n_out].iter().map(|p| p.eval(t)).collect(),
            quantities: self.chaos[n_out..]
                .iter()
                .map(|p| p.eval_column(0, t))
                .collect(),
        }
    }

    /// `eval` as CSV: `name,time,value`, one row per output and time, then one per quantity
    /// (empty time). Numbers as every CSV of the driver writes them
    /// (the shortest round-trip form of every CSV of the driver).
    pub fn eval_csv(&self, x: &[f64]) -> String {
        let v = self.eval(x);
        let mut text = String::from("name,time,value\n");
        for (o, vals) in self.file.outputs.iter().zip(&v.outputs) {
            let times = o.times.as_deref().unwrap_or(&[]);
            for (t, y) in times.iter().zip(vals) {
                crate::text::csv::push_field(&mut text, &o.name);
                text.push(',');
                push_shortest(&mut text, *t);
                text.push(',');
                push_shortest(&mut text, *y);
                text.push('\n');
            }
        }
        for (q, y) in self.file.quantities.iter().zip(&v.quantities) {
            crate::text::csv::push_field(&mut text, &q.name);
            text.push_str(",,");
            push_shortest(&mut text, *y);
            text.push('\n');
        }
        text
    }

    /// The columns of `sample` for the requested `times` (s): per output (that has times),
    /// `(output index, time index, NAME@TIME)` with TIME the communication point nearest to
    /// each requested time (default: the last one). A time outside an output's time grid,
    /// or two times that fall on one communication point, are refused.
    fn sample_columns(&self, times: &[f64]) -> Result<Vec<(usize, usize, String)>, SurrogateError> {
        let mut picks = Vec::new();
        for (o, chaos) in self.file.outputs.iter().enumerate() {
            let ts = chaos.times.as_deref().unwrap_or(&[]);
            let (Some(&first), Some(&last)) = (ts.first(), ts.last()) else {
                continue;
            };
            let mut wanted: Vec<(f64, usize)> = Vec::new();
            for &t in times {
                if !(first..=last).contains(&t) {
                    return Err(SurrogateError::Input(format!(
                        "time {} s is outside the time grid of output '{}' ({} to {} s)",
                        shortest(t),
                        chaos.name,
                        shortest(first),
                        shortest(last)
                    )));
                }
                let k = (0..ts.len())
                    .min_by(|&a, &b| (ts[a] - t).abs().total_cmp(&(ts[b] - t).abs()))
                    .unwrap_or(0);
                if let Some((u, _)) = wanted.iter().find(|&&(_, j)| j == k) {
                    return Err(SurrogateError::Input(format!(
                        "times {} s and {} s both fall on the communication point {} s of \
                         output '{}': give each time once",
                        shortest(*u),
                        shortest(t),
                        shortest(ts[k]),
                        chaos.name
                    )));
                }
                wanted.push((t, k));
            }
            if times.is_empty() {
                wanted.push((last, ts.len() - 1));
            }
            for (_, k) in wanted {
                picks.push((o, k, format!("{}@{}", chaos.name, shortest(ts[k]))));
            }
        }
        if picks.is_empty() && !times.is_empty() {
            return Err(SurrogateError::Input(
                "times given, but the surrogate has no output over time (only scalar \
                 quantities)"
                    .into(),
            ));
        }
        Ok(picks)
    }

    /// `sample` as CSV: the inputs, the quantities, then each output at the communication
    /// points nearest to `times` (default: its last), as columns `NAME@TIME` (TIME the
    /// communication point). Refuses a time outside an output's time grid, and two times
    /// that fall on one communication point.
    pub fn sample_csv(&self, n: usize, seed: u64, times: &[f64]) -> Result<String, SurrogateError> {
        let mut bytes = Vec::new();
        self.write_sample_csv(n, seed, times, &mut bytes, "memory")?;
        Ok(String::from_utf8(bytes).expect("CSV text is UTF-8"))
    }

    /// [`Surrogate::sample_csv`] written to `w` row by row as the points are drawn: the memory
    /// does not grow with `n` (the draws are those of [`Surrogate::sample`], point `i` from
    /// the stream `(seed, i)`). `target` names `w` in an error.
    pub fn write_sample_csv(
        &self,
        n: usize,
        seed: u64,
        times: &[f64],
        w: &mut dyn std::io::Write,
        target: &str,
    ) -> Result<(), SurrogateError> {
        let picks = self.sample_columns(times)?;
        let mut header: Vec<String> = self.inputs.iter().map(|p| p.name.clone()).collect();
        header.extend(self.file.quantities.iter().map(|q| q.name.clone()));
        header.extend(picks.iter().map(|p| p.2.clone()));
        let mut text = String::new();
        let header: Vec<&str> = header.iter().map(String::as_str).collect();
        crate::text::csv::push_header(&mut text, &header);
        let families: Vec<Family> = self.file.inputs.iter().map(|i| i.family).collect();
        let laws: Vec<_> = families.iter().map(Family::law).collect();
        let mut t = vec![0.0; families.len()];
        let io = |source| SurrogateError::Io {
            path: target.to_owned(),
            source,
        };
        for i in 0..n {
            germ_draw(&families, &laws, seed, i, &mut t);
            let x = self.inputs.to_physical(self.file.germ, &t);
            let n_out = self.file.outputs.len();
            // Only the picked times of each output are evaluated (the same sums as eval_germ).
            let values = x
                .iter()
                .copied()
                .chain(self.chaos[n_out..].iter().map(|p| p.eval_column(0, &t)))
                .chain(
                    picks
                        .iter()
                        .map(|&(o, k, _)| self.chaos[o].eval_column(k, &t)),
                );
            for (j, y) in values.enumerate() {
                if j > 0 {
                    text.push(',');
                }
                push_shortest(&mut text, y);
            }
            text.push('\n');
            if text.len() >= 1 << 16 {
                w.write_all(text.as_bytes()).map_err(io)?;
                text.clear();
            }
        }
        w.write_all(text.as_bytes()).map_err(io)?;
        w.flush().map_err(io)
    }

    /// `n` random points of the inputs' joint law with the surrogate's values there: point
    /// `i` comes from the stream `(seed, i)` only (`germ_draws`).
    pub fn sample(&self, n: usize, seed: u64) -> Vec<(Vec<f64>, SurrogateValues)> {
        let families: Vec<Family> = self.file.inputs.iter().map(|i| i.family).collect();
        germ_draws(&families, n, seed)
            .into_iter()
            .map(|t| {
                let x = self.inputs.to_physical(self.file.germ, &t);
                (x, self.eval_germ(&t))
            })
            .collect()
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::uq::random_inputs::CorrelationPair;

    fn inputs(correlated: bool) -> RandomInputs {
        let parameters = vec![
            RandomParameter::new("a", Distribution::normal(2.0, 0.5).unwrap()),
            RandomParameter::new("b", Distribution::uniform(0.0, 4.0).unwrap()),
        ];
        let pairs = if correlated {
            vec![CorrelationPair {
                between: ["a".into(), "b".into()],
                rho: 0.4,
            }]
        } else {
            vec![]
        };
        let correlation = Correlation::new(&parameters, pairs).unwrap();
        RandomInputs {
            parameters,
            correlation,
        }
    }

    /// f(t) = 1 + 2 p1(t_a) + 0.5 p1(t_b) p1(t_a), Hermite x Legendre (Askey germs).
    fn chaos() -> NamedChaos {
        let set = MultiIndexSet::from_indices(2, vec![vec![0, 0], vec![1, 0], vec![1, 1]]).unwrap();
        let basis = Basis::new(vec![Family::Hermite, Family::Legendre], set).unwrap();
        NamedChaos {
            name: "f".into(),
            times: Some(vec![0.0]),
            pce: Pce::new(basis, DMatrix::from_column_slice(3, 1, &[1.0, 2.0, 0.5])).unwrap(),
            error: None,
        }
    }

    #[test]
    fn a_written_surrogate_reads_back_and_evaluates_at_physical_values() {
        for correlated in [false, true] {
            let ins = inputs(correlated);
            let file = SurrogateFile::new("s", "sparse_grid", Germ::Askey, &ins, &[chaos()], &[]);
            let text = serde_json::to_string(&file).unwrap();
            assert!(
                text.contains(r#""map":"affine","offset":2.0,"scale":0.5"#),
                "{text}"
            );
            let s = Surrogate::new(serde_json::from_str(&text).unwrap()).unwrap();
            // At physical values: germs by the inverse map, then the chaos.
            let x = [2.5, 3.0];
            let t = ins.to_germ(Germ::Askey, &x);
            if !correlated {
                assert_eq!(t, vec![1.0, 0.5]);
            }
            let want = 1.0 + 2.0 * t[0] + 0.5 * t[0] * (3f64.sqrt() * t[1]);
            assert!((s.eval(&x).outputs[0][0] - want).abs() < 1e-12);
            // Draws: the inputs' values and the chaos at the same germ points.
            let draws = s.sample(50, 1);
            assert_eq!(draws.len(), 50);
            for (x, v) in &draws {
                assert!((s.eval(x).outputs[0][0] - v.outputs[0][0]).abs() < 1e-9);
                assert!((0.0..=4.0).contains(&x[1]));
            }
            assert_eq!(
                s.sample_csv(50, 1, &[]).unwrap(),
                s.sample_csv(50, 1, &[]).unwrap()
            );
        }
    }

    /// A chaos of output `f` on the times 0, 0.5, 1 s: the constant `c[k]` at time k.
    fn constant_over_time(c: [f64; 3]) -> NamedChaos {
        let set = MultiIndexSet::from_indices(2, vec![vec![0, 0]]).unwrap();
        let basis = Basis::new(vec![Family::Hermite, Family::Legendre], set).unwrap();
        NamedChaos {
            name: "f".into(),
            times: Some(vec![0.0, 0.5, 1.0]),
            pce: Pce::new(basis, DMatrix::from_row_slice(1, 3, &c)).unwrap(),
            error: None,
        }
    }

    /// F8: `surrogate sample --time` took any time (5 s on a 0–1 s grid) and wrote two
    /// columns `f@1` for two times near 1 s.
    #[test]
    fn sample_times_outside_the_grid_or_on_one_point_are_refused() {
        let file = SurrogateFile::new(
            "s",
            "sparse_grid",
            Germ::Askey,
            &inputs(false),
            &[constant_over_time([1.0, 2.0, 3.0])],
            &[],
        );
        let s = Surrogate::new(file).unwrap();
        for t in [5.0, -0.1, 1.0000001, f64::NAN] {
            let e = s.sample_csv(2, 1, &[t]).unwrap_err().to_string();
            assert!(
                e.contains("outside the time grid of output 'f' (0 to 1 s)"),
                "{e}"
            );
        }
        let e = s.sample_csv(2, 1, &[0.96, 1.0]).unwrap_err().to_string();
        assert!(
            e.contains("0.96 s and 1 s both fall on the communication point 1 s"),
            "{e}"
        );
        // Columns by the communication point used: 0.2 s → 0, 0.3 s → 0.5, 1 s → 1.
        let text = s.sample_csv(2, 1, &[0.3, 1.0, 0.2]).unwrap();
        let mut lines = text.lines();
        assert_eq!(lines.next().unwrap(), "a,b,f@0.5,f@1,f@0");
        for line in lines {
            assert!(line.ends_with(",2,3,1"), "{line}");
        }
        // The ends of the grid are inside it; no time: the last.
        let header = |t: &[f64]| {
            s.sample_csv(1, 1, t)
                .unwrap()
                .lines()
                .next()
                .unwrap()
                .to_owned()
        };
        assert_eq!(header(&[0.0, 1.0]), "a,b,f@0,f@1");
        assert_eq!(header(&[]), "a,b,f@1");
        // Only a scalar quantity: a time has nothing to choose.
        let mut q = constant_over_time([1.0, 2.0, 3.0]);
        q.times = None;
        q.pce = chaos().pce;
        let file = SurrogateFile::new("s", "scm", Germ::Askey, &inputs(false), &[], &[q]);
        let s = Surrogate::new(file).unwrap();
        assert!(s
            .sample_csv(1, 1, &[0.5])
            .unwrap_err()
            .to_string()
            .contains("no output over time"));
        assert!(s.sample_csv(1, 1, &[]).unwrap().starts_with("a,b,f\n"));
    }

    /// F9: `surrogate eval` printed 5.19e-17 as a 35-character decimal; numbers are written
    /// as in every CSV of the driver (exponent notation below 1e-4 and from 1e16).
    #[test]
    fn eval_and_sample_write_numbers_like_the_other_csv_files() {
        let file = SurrogateFile::new(
            "s",
            "scm",
            Germ::Askey,
            &inputs(false),
            &[constant_over_time([5.1906094329251493e-17, 0.25, 1.5e16])],
            &[],
        );
        let s = Surrogate::new(file).unwrap();
        assert_eq!(
            s.eval_csv(&[2.0, 2.0]),
            "name,time,value\nf,0,5.1906094329251493e-17\nf,0.5,0.25\nf,1,1.5e16\n"
        );
        let text = s.sample_csv(1, 1, &[0.0, 1.0]).unwrap();
        assert!(
            text.lines()
                .nth(1)
                .unwrap()
                .ends_with(",5.1906094329251493e-17,1.5e16"),
            "{text}"
        );
    }

    #[test]
    fn foreign_files_and_bad_points_are_refused() {
        let ins = inputs(false);
        let mut file = SurrogateFile::new("s", "scm", Germ::Askey, &ins, &[chaos()], &[]);
        let s = Surrogate::new(file.clone()).unwrap();
        assert!(s.point(&[("zz".into(), 1.0)]).is_err());
        assert!(s.point(&[("b".into(), 5.0)]).is_err());
        assert_eq!(s.point(&[("a".into(), 1.0)]).unwrap(), vec![1.0, 2.0]);
        file.version = 2;
        assert!(Surrogate::new(file.clone()).is_err());
        file.version = VERSION;
        file.outputs[0].coefficients[0].pop();
        assert!(Surrogate::new(file).is_err());
    }

    fn refusal(file: SurrogateFile) -> String {
        match Surrogate::new(file) {
            Err(SurrogateError::Invalid(m)) => m,
            other => panic!("not refused: {other:?}"),
        }
    }

    #[test]
    fn damaged_surrogate_files_are_refused_on_loading_not_when_sampled() {
        let good = SurrogateFile::new("s", "scm", Germ::Askey, &inputs(false), &[chaos()], &[]);
        // Fewer coefficient vectors than times (sample used to index past them).
        let mut f = good.clone();
        f.outputs[0].times = Some(vec![0.0, 1.0, 2.0]);
        assert!(refusal(f).contains("1 coefficient vectors for 3 times"));
        let mut f = good.clone();
        f.outputs[0].times = None;
        assert!(refusal(f).contains("needs its times"));
        let mut f = good.clone();
        f.outputs[0].times = Some(vec![f64::NAN]);
        assert!(refusal(f).contains("finite and increasing"));
        // A huge degree (used to allocate for it).
        let mut f = good.clone();
        f.outputs[0].multi_indices[2] = vec![4_000_000_000, 0];
        assert!(refusal(f).contains("degree above 1000"));
        let mut f = good.clone();
        f.outputs[0].coefficients[0][1] = f64::INFINITY;
        assert!(refusal(f).contains("not a finite number"));
        // A quantity has one coefficient vector.
        let mut f = good.clone();
        let mut q = f.outputs[0].clone();
        q.times = None;
        q.coefficients.push(q.coefficients[0].clone());
        f.quantities.push(q);
        assert!(refusal(f).contains("2 coefficient vectors for 1 value"));
        // The uniform germ (Monte Carlo designs) has no chaos: draws were NaN.
        let mut f = good.clone();
        f.germ = Germ::Uniform;
        assert!(refusal(f).contains("not a chaos germ"));
        // Families and maps that are not those the evaluation uses.
        let mut f = good.clone();
        f.inputs[1].family = Family::Hermite;
        let m = refusal(f);
        assert!(m.contains("input 'b'"));
        // README audit F18: the message spoke Rust (`family Hermite with map Affine { .. }`),
        // not the file's `"family":"hermite","map":"affine"`.
        assert!(m.contains(r#"{"family":"hermite","map":"affine","#), "{m}");
        assert!(m.contains(r#"germ "askey""#), "{m}");
        assert!(!m.contains("Affine") && !m.contains("Hermite"), "{m}");
        let mut f = good.clone();
        f.inputs[0].map = InputMap::Affine {
            offset: 2.0,
            scale: -1.0,
        };
        assert!(refusal(f).contains("input 'a'"));
        let mut f = good.clone();
        f.inputs[1].name = "a".into();
        assert!(refusal(f).contains("listed twice"));
        assert!(Surrogate::new(good).is_ok());
    }

    #[test]
    fn a_repeated_at_is_refused_not_the_last_value_kept() {
        let file = SurrogateFile::new("s", "scm", Germ::Askey, &inputs(false), &[chaos()], &[]);
        let s = Surrogate::new(file).unwrap();
        let err = s
            .point(&[("a".into(), 1.0), ("b".into(), 1.0), ("a".into(), 2.0)])
            .unwrap_err();
        assert!(
            err.to_string().contains("'a' is given more than once"),
            "{err}"
        );
    }

    #[test]
    fn sample_written_row_by_row_is_the_sample_drawn_at_once() {
        let file = SurrogateFile::new("s", "scm", Germ::Askey, &inputs(true), &[chaos()], &[]);
        let s = Surrogate::new(file).unwrap();
        // More than one 64 KiB chunk of text.
        let n = 5000;
        let text = s.sample_csv(n, 3, &[]).unwrap();
        assert!(text.len() > 1 << 17, "{}", text.len());
        let draws = s.sample(n, 3);
        let rows: Vec<&str> = text.lines().skip(1).collect();
        assert_eq!(rows.len(), n);
        for (row, (x, v)) in rows.iter().zip(&draws) {
            let got: Vec<f64> = row.split(',').map(|c| c.parse().unwrap()).collect();
            let want: Vec<f64> = x.iter().chain(&v.quantities).copied().collect();
            assert_eq!(&got[..want.len()], &want[..]);
            assert_eq!(got[want.len()], v.outputs[0][0]);
        }
        // A writer that fails names its target.
        struct Full;
        impl std::io::Write for Full {
            fn write(&mut self, _: &[u8]) -> std::io::Result<usize> {
                Err(std::io::Error::other("no space left"))
            }
            fn flush(&mut self) -> std::io::Result<()> {
                Ok(())
            }
        }
        let err = s
            .write_sample_csv(10, 3, &[], &mut Full, "draws.csv")
            .unwrap_err();
        assert_eq!(err.to_string(), "draws.csv: no space left");
    }
}
