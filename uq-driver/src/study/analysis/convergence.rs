//! Mean and Std against the work spent: the chaos truncated at each order, or the running
//! estimates over the runs.

use crate::results::Convergence;
use crate::uq::method::Estimate;

/// Mean and Std against the work spent: for a chaos, those of the expansion truncated at
/// total order 0, 1, … (terms of a full-tensor projection do not depend on each other, so
/// the truncation is the lower-order projection); for runs, the running estimates over the
/// first n runs in design order (at about 30 values of n on a log scale).
pub(super) fn convergence(estimate: &Estimate, col: usize, valid: &[f64]) -> Option<Convergence> {
    if let Some(pce) = &estimate.chaos {
        // An orthonormal basis: each term's variance is its coefficient squared.
        let set = pce.set();
        let c0 = set.position(&vec![0; set.dim()]);
        let mean = c0.map_or(0.0, |t| pce.coeffs[(t, col)]);
        let order = set.order();
        let mut of_order = vec![0.0_f64; order + 1];
        for (t, k) in set.indices().iter().enumerate() {
            if Some(t) != c0 {
                let degree: usize = k.iter().sum();
                of_order[degree] += pce.coeffs[(t, col)].powi(2);
            }
        }
        let cumulative: Vec<f64> = of_order
            .iter()
            .scan(0.0_f64, |acc, v| {
                *acc += v;
                Some(acc.sqrt())
            })
            .collect();
        return Some(Convergence {
            axis: "chaos order".into(),
            x: (0..=order).map(|o| o as f64).collect(),
            mean: vec![mean; order + 1],
            std: cumulative,
            std_of_order: of_order.iter().map(|v: &f64| v.sqrt()).collect(),
            std_error_mean: Vec::new(),
        });
    }
    if valid.len() < 4 {
        return None;
    }
    let n = valid.len();
    let mut points: Vec<usize> = (0..=30)
        .map(|i| (2.0 * (n as f64 / 2.0).powf(i as f64 / 30.0)).round() as usize)
        .collect();
    points.dedup();
    let (mut mean, mut std) = (Vec::new(), Vec::new());
    let (mut m, mut m2) = (0.0, 0.0);
    let mut next = 0;
    for (i, &x) in valid.iter().enumerate() {
        // Welford's running mean and sum of squared deviations.
        let d = x - m;
        m += d / (i + 1) as f64;
        m2 += d * (x - m);
        if next < points.len() && i + 1 == points[next] {
            mean.push(m);
            std.push((m2 / i.max(1) as f64).sqrt());
            next += 1;
        }
    }
    Some(Convergence {
        axis: "runs".into(),
        x: points.iter().map(|&p| p as f64).collect(),
        mean,
        std,
        std_of_order: Vec::new(),
        std_error_mean: Vec::new(),
    })
}
