//! From finished runs to statistics: moments over time, quantiles, PDF evolution, chaos
//! coefficients and Sobol' indices (SCM, SGM), and scalar quantities of interest.

use nalgebra::DMatrix;
use serde::Serialize;

use super::design::Design;
use super::spec::{MethodKind, Study};
use super::store::Record;
use crate::qoi::scalar::Code;
use crate::qoi::{kde, moments};
use crate::uq::pce::{MultiIndexSet, Pce};
use crate::uq::rng;

/// First-order and total Sobol' indices over time, each `[time][parameter]`.
pub type SobolSeries = (Vec<Vec<f64>>, Vec<Vec<f64>>);

/// Statistics of one output variable over time.
#[derive(Clone, Debug)]
pub struct OutputStats {
    /// Variable name.
    pub name: String,
    /// Communication points (s).
    pub times: Vec<f64>,
    /// Mean over time.
    pub mean: Vec<f64>,
    /// Standard deviation over time (SCM: from the quadrature; SGM: from the chaos;
    /// MC/LHS: unbiased sample Std).
    pub std: Vec<f64>,
    /// Quantiles over time: (level, values).
    pub quantiles: Vec<(f64, Vec<f64>)>,
    /// SCM: Std from the chaos coefficients (truncated at the study's order).
    pub std_pce: Option<Vec<f64>>,
    /// SCM/SGM: first-order and total Sobol' indices over time (`[time][parameter]`).
    pub sobol: Option<SobolSeries>,
    /// PDF evolution: times of the columns.
    pub pdf_times: Vec<f64>,
    /// Grid of the densities.
    pub pdf_grid: Vec<f64>,
    /// `pdf[i][j]`: density at `pdf_times[i]`, `pdf_grid[j]`.
    pub pdf: Vec<Vec<f64>>,
}

/// Statistics of one scalar quantity of interest.
#[derive(Clone, Debug, Serialize)]
pub struct ScalarStats {
    /// Quantity name.
    pub name: String,
    /// Mean (SCM: quadrature; MC/LHS: sample mean over valid runs).
    pub mean: f64,
    /// Standard deviation.
    pub std: f64,
    /// Standard error of the mean (MC/LHS: std/√n; SCM: 0, quadrature).
    pub std_error_mean: f64,
    /// Runs with a valid value.
    pub n_valid: usize,
    /// Critical speed: runs that never hunt.
    pub n_never_hunts: usize,
    /// Critical speed: runs whose oscillation never dies out.
    pub n_never_stops: usize,
    /// (level, value) quantiles (SCM: of the chaos surrogate).
    pub quantiles: Vec<(f64, f64)>,
    /// Smallest and largest value over the runs.
    pub min: f64,
    /// Largest.
    pub max: f64,
    /// P(q > limit): (limit, p, standard error of p).
    pub exceedance: Vec<(f64, f64, f64)>,
    /// PDF grid.
    pub pdf_x: Vec<f64>,
    /// PDF values (KDE of the runs, or of the chaos surrogate for SCM).
    pub pdf: Vec<f64>,
    /// The valid values of the runs (for histograms).
    #[serde(skip)]
    pub samples: Vec<f64>,
    /// The samples the PDF and quantiles come from (runs, or the surrogate).
    #[serde(skip)]
    pub density_samples: Vec<f64>,
    /// SCM: first-order Sobol' indices per parameter.
    pub sobol_first: Option<Vec<f64>>,
    /// SCM: total Sobol' indices per parameter.
    pub sobol_total: Option<Vec<f64>>,
}

/// Draws of the standard-normal germ for surrogate sampling, as basis values (n × P).
fn surrogate_basis(study: &Study, basis: &MultiIndexSet) -> DMatrix<f64> {
    let n = study.file.analysis.surrogate_samples.max(2);
    let d = basis.dim();
    let p = basis.len();
    let mut psi = DMatrix::<f64>::zeros(n, p);
    let mut z = vec![0.0; d];
    let mut row = vec![0.0; p];
    // Streams offset from the design's so the surrogate draws are independent of it.
    let seed = study.file.seed ^ 0x5eed_5a4d_0000_0000;
    for i in 0..n {
        let mut r = rng::stream(seed, i as u64);
        for zj in z.iter_mut() {
            *zj = rng::standard_normal(&mut r);
        }
        basis.eval(&z, &mut row);
        for (j, v) in row.iter().enumerate() {
            psi[(i, j)] = *v;
        }
    }
    psi
}

/// Column indices of at most `max` evenly spaced columns out of `n`, always with the last.
fn thinned(n: usize, max: usize) -> Vec<usize> {
    if n <= max {
        return (0..n).collect();
    }
    let step = n.div_ceil(max);
    let mut v: Vec<usize> = (0..n).step_by(step).collect();
    if *v.last().expect("n > 0") != n - 1 {
        v.push(n - 1);
    }
    v
}

/// Quantiles and PDF evolution from a samples matrix (rows: samples, columns: times).
#[allow(clippy::too_many_arguments)]
fn finish(
    study: &Study,
    name: &str,
    times: &[f64],
    mean: Vec<f64>,
    std: Vec<f64>,
    std_pce: Option<Vec<f64>>,
    pce: Option<&Pce>,
    samples: &DMatrix<f64>,
) -> OutputStats {
    let a = &study.file.analysis;
    let cols = moments::column_quantiles(samples, &a.quantiles);
    let quantiles = a
        .quantiles
        .iter()
        .enumerate()
        .map(|(qi, &p)| (p, cols.iter().map(|c| c[qi]).collect()))
        .collect();
    let picked = thinned(times.len(), a.pdf_times);
    let (mut lo, mut hi) = (f64::INFINITY, f64::NEG_INFINITY);
    for &k in &picked {
        for v in samples.column(k).iter() {
            lo = lo.min(*v);
            hi = hi.max(*v);
        }
    }
    let pad = 0.05 * (hi - lo).max(1e-12 * hi.abs().max(1.0));
    let grid = kde::auto_grid(lo - pad, hi + pad, a.pdf_grid);
    let pdf: Vec<Vec<f64>> = picked
        .iter()
        .map(|&k| {
            let col: Vec<f64> = samples.column(k).iter().copied().collect();
            kde::gaussian_kde(&col, None, &grid, kde::silverman_bandwidth(&col))
        })
        .collect();
    let sobol = pce.map(|p| {
        let first = (0..times.len()).map(|k| p.sobol_first(k)).collect();
        let total = (0..times.len()).map(|k| p.sobol_total(k)).collect();
        (first, total)
    });
    OutputStats {
        name: name.to_owned(),
        times: times.to_vec(),
        mean,
        std,
        quantiles,
        std_pce,
        sobol,
        pdf_times: picked.iter().map(|&k| times[k]).collect(),
        pdf_grid: grid,
        pdf,
    }
}

/// Statistics of an output known by its chaos (SGM).
pub fn stats_from_pce(study: &Study, name: &str, pce: &Pce) -> OutputStats {
    let times = study.file.experiment.times();
    let samples = surrogate_basis(study, &pce.basis) * &pce.coeffs;
    finish(
        study,
        name,
        &times,
        pce.mean(),
        pce.std(),
        None,
        Some(pce),
        &samples,
    )
}

/// Indices of the successful runs.
fn ok_points(records: &[Option<Record>]) -> Vec<usize> {
    (0..records.len())
        .filter(|&i| matches!(records[i], Some(Record::Ok(_))))
        .collect()
}

/// Analyses every output of a sampled or collocated study. `records` must hold a record for
/// every point.
pub fn analyse(
    study: &Study,
    design: &Design,
    records: &[Option<Record>],
) -> Result<Vec<OutputStats>, String> {
    let times = study.file.experiment.times();
    let nt = times.len();
    let ok = ok_points(records);
    let needed = if design.method == MethodKind::Nominal {
        1
    } else {
        2
    };
    if ok.len() < needed {
        return Err(format!(
            "only {} successful runs: nothing to analyse",
            ok.len()
        ));
    }
    let mut out = Vec::new();
    for (o, name) in study.file.outputs.variables.iter().enumerate() {
        let data = DMatrix::from_fn(ok.len(), nt, |r, k| match &records[ok[r]] {
            Some(Record::Ok(v)) => v[o * nt + k],
            _ => unreachable!("filtered above"),
        });
        match (design.method, &design.weights) {
            (MethodKind::Scm, Some(w)) => {
                if ok.len() != design.len() {
                    return Err(
                        "a collocation node is missing: refusing to drop a weighted node".into(),
                    );
                }
                let (mean, std) = moments::weighted_mean_std(&data, w);
                let pce = project(study, design, w, &data)?;
                let samples = surrogate_basis(study, &pce.basis) * &pce.coeffs;
                out.push(finish(
                    study,
                    name,
                    &times,
                    mean,
                    std,
                    Some(pce.std()),
                    Some(&pce),
                    &samples,
                ));
            }
            (MethodKind::Nominal, Some(w)) => {
                let (mean, std) = moments::weighted_mean_std(&data, w);
                out.push(finish(study, name, &times, mean, std, None, None, &data));
            }
            _ => {
                let (mean, std) = moments::sample_mean_std(&data);
                out.push(finish(study, name, &times, mean, std, None, None, &data));
            }
        }
    }
    Ok(out)
}

fn project(study: &Study, design: &Design, w: &[f64], data: &DMatrix<f64>) -> Result<Pce, String> {
    let basis = MultiIndexSet::total_order(study.parameters.len(), design.order);
    Pce::project(basis, &design.germ, w, data, &design.nodes_per_dim).map_err(|e| e.to_string())
}

/// Analyses the scalar quantities of interest.
pub fn analyse_scalars(
    study: &Study,
    design: &Design,
    records: &[Option<Record>],
) -> Result<Vec<ScalarStats>, String> {
    let nt = study.file.experiment.times().len();
    let base = study.file.outputs.variables.len() * nt;
    let ok = ok_points(records);
    let a = &study.file.analysis;
    let mut out = Vec::new();
    for (qi, q) in study.file.qoi.iter().enumerate() {
        let mut values = Vec::with_capacity(ok.len());
        let mut codes = Vec::with_capacity(ok.len());
        for &i in &ok {
            if let Some(Record::Ok(v)) = &records[i] {
                values.push(v[base + 2 * qi]);
                codes.push(Code::from_f64(v[base + 2 * qi + 1]));
            }
        }
        let n_never_hunts = codes.iter().filter(|c| **c == Code::NeverHunts).count();
        let n_never_stops = codes.iter().filter(|c| **c == Code::NeverStops).count();
        let valid: Vec<f64> = values
            .iter()
            .zip(&codes)
            .filter(|(_, c)| **c == Code::Ok)
            .map(|(v, _)| *v)
            .collect();
        if valid.is_empty() {
            return Err(format!(
                "quantity '{}': no run gave a value ({n_never_hunts} never hunt, {n_never_stops} never stop)",
                q.name()
            ));
        }
        let (mean, std, sem, density_samples, sobol_first, sobol_total) = match (
            design.method,
            &design.weights,
        ) {
            (MethodKind::Scm, Some(w)) => {
                if valid.len() != design.len() {
                    return Err(format!(
                        "quantity '{}': {} of {} collocation nodes have no value ({n_never_hunts} never hunt, \
                         {n_never_stops} never stop); a chaos cannot be projected without them — use LHS/MC, \
                         or change the detection settings or the run length",
                        q.name(),
                        design.len() - valid.len(),
                        design.len()
                    ));
                }
                let data = DMatrix::from_column_slice(valid.len(), 1, &valid);
                let (m, s) = moments::weighted_mean_std(&data, w);
                let pce = project(study, design, w, &data)?;
                let sur = (surrogate_basis(study, &pce.basis) * &pce.coeffs)
                    .column(0)
                    .iter()
                    .copied()
                    .collect();
                (
                    m[0],
                    s[0],
                    0.0,
                    sur,
                    Some(pce.sobol_first(0)),
                    Some(pce.sobol_total(0)),
                )
            }
            (MethodKind::Nominal, _) => (valid[0], 0.0, 0.0, valid.clone(), None, None),
            _ => {
                let sum = moments::ScalarSummary::from_samples(&valid);
                (
                    sum.mean,
                    sum.std,
                    sum.std_error_mean,
                    valid.clone(),
                    None,
                    None,
                )
            }
        };
        let mut sorted = density_samples.clone();
        sorted.sort_by(f64::total_cmp);
        let quantiles = a
            .quantiles
            .iter()
            .map(|&p| (p, moments::quantile(&sorted, p)))
            .collect();
        let (lo, hi) = (sorted[0], sorted[sorted.len() - 1]);
        let bw = kde::silverman_bandwidth(&sorted);
        let grid = kde::auto_grid(lo - 3.0 * bw, hi + 3.0 * bw, a.pdf_grid);
        let pdf = kde::gaussian_kde(&sorted, None, &grid, bw);
        let exceedance = q
            .limits()
            .iter()
            .map(|&l| {
                let (p, se) = moments::exceedance_probability(&density_samples, l);
                (l, p, se)
            })
            .collect();
        out.push(ScalarStats {
            name: q.name().to_owned(),
            mean,
            std,
            std_error_mean: sem,
            n_valid: valid.len(),
            n_never_hunts,
            n_never_stops,
            quantiles,
            min: valid.iter().copied().fold(f64::INFINITY, f64::min),
            max: valid.iter().copied().fold(f64::NEG_INFINITY, f64::max),
            exceedance,
            pdf_x: grid,
            pdf,
            samples: valid,
            density_samples,
            sobol_first,
            sobol_total,
        });
    }
    Ok(out)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn thinning_keeps_ends() {
        assert_eq!(thinned(5, 10), vec![0, 1, 2, 3, 4]);
        let t = thinned(501, 100);
        assert_eq!(t[0], 0);
        assert_eq!(*t.last().unwrap(), 500);
        assert!(t.len() <= 101);
    }
}
