//! One-dimensional quadrature rules by *level*, nested and not, for sparse grids.
//!
//! Levels count from 0 (level 0 is the one-point rule at the germ's centre). Weights sum
//! to 1: the rules integrate against the germ's probability measure, N(0, 1) for
//! [`RuleKind::GenzKeister`] and [`RuleKind::GaussHermite`], U(-1, 1) (density 1/2) for
//! the others.
//!
//! | rule | nested | points at level 0, 1, 2, ... | degree of exactness |
//! | --- | --- | --- | --- |
//! | Genz–Keister | yes | 1, 3, 9, 19, 35 | 1, 5, 15, 29, 51 |
//! | Clenshaw–Curtis | yes | 1, 3, 5, 9, 17, ..., `2^l + 1` | 1, 3, 5, 9, 17, ..., `2^l + 1` |
//! | Gauss–Patterson | yes | 1, 3, 7, 15, 31, 63 | 1, 5, 11, 23, 47, 95 (`3 * 2^l - 1`) |
//! | Gauss–Legendre | no | `l + 1` | `2l + 1` |
//! | Gauss–Hermite | no | `l + 1` | `2l + 1` |
//! | Gauss rule of an Askey family (Laguerre, Jacobi germs) | no | `l + 1` | `2l + 1` |
//!
//! Genz–Keister (J. Comput. Appl. Math. 71, 1996; generators 1+2+6+10+16) and
//! Gauss–Patterson (Math. Comp. 22, 1968) rules are Kronrod–Patterson extensions:
//! each level keeps the previous nodes and adds the roots of the polynomial `q` of
//! degree `m` orthogonal, for the weight `p(t) dmu(t)` (`p` = the node polynomial of
//! the previous level), to all polynomials of degree `< m`. Gauss–Patterson rules are
//! computed so, in the orthonormal Legendre basis (agreeing with Patterson's published
//! figures to 1e-15). For the Gaussian weight the same construction in double precision
//! loses digits (about 1e-11 at 35 nodes: the moment problem is ill-conditioned), so the
//! Genz–Keister nodes and weights are the published table of figures (Genz, as tabulated
//! by Burkardt, 17 digits); the tests check the table against the construction and
//! against the exact moments of N(0, 1).

// The published tables keep all their digits.
#![allow(clippy::excessive_precision)]

use std::sync::OnceLock;

use nalgebra::{DMatrix, DVector};

use crate::uq::pce::askey::Family;
use crate::uq::quadrature::symmetrize_nodes;

/// Errors of the rule constructors.
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
pub enum RuleError {
    /// The level is beyond the rule's table.
    #[error("{rule} has levels 0..={max}; level {level} was requested")]
    LevelTooHigh {
        /// Rule name.
        rule: &'static str,
        /// Requested level.
        level: usize,
        /// Highest level available.
        max: usize,
    },
    /// The Kronrod–Patterson extension failed (no real, distinct new nodes).
    #[error("the Patterson extension of {old} nodes by {new} failed: {why}")]
    Extension {
        /// Previous node count.
        old: usize,
        /// Added node count.
        new: usize,
        /// What went wrong.
        why: String,
    },
}

/// A one-dimensional rule: nodes ascending, weights summing to 1.
#[derive(Clone, Debug, PartialEq)]
pub struct Rule1d {
    /// Nodes, ascending.
    pub nodes: Vec<f64>,
    /// Weights (probability measure of the germ).
    pub weights: Vec<f64>,
    /// Degree of polynomial exactness.
    pub exactness: usize,
}

/// A row of a rule's table ([`RuleKind::table`], which serves the tests).
#[cfg(test)]
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct LevelInfo {
    /// Level (from 0).
    pub level: usize,
    /// Number of nodes.
    pub points: usize,
    /// Degree of exactness.
    pub exactness: usize,
}

/// The one-dimensional rules available for sparse grids.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum RuleKind {
    /// Nested rule for the N(0, 1) germ (Genz–Keister 1+2+6+10+16).
    GenzKeister,
    /// Nested Clenshaw–Curtis rule for the U(-1, 1) germ.
    ClenshawCurtis,
    /// Nested Gauss–Patterson rule for the U(-1, 1) germ.
    GaussPatterson,
    /// Gauss–Legendre, `level + 1` points (not nested).
    GaussLegendre,
    /// Probabilists' Gauss–Hermite, `level + 1` points (not nested).
    GaussHermite,
    /// The Gauss rule of an Askey family's germ (e.g. Gauss–Laguerre for a Gamma germ,
    /// Gauss–Jacobi for a Beta germ), `level + 1` points (not nested).
    Gauss(Family),
}

/// Genz–Keister points per level.
const GK_POINTS: [usize; 5] = [1, 3, 9, 19, 35];
/// Genz–Keister degrees of exactness per level.
const GK_EXACTNESS: [usize; 5] = [1, 5, 15, 29, 51];
/// Highest Gauss–Patterson level (63 points).
const GP_MAX_LEVEL: usize = 5;
/// Highest Clenshaw–Curtis level (`2^12 + 1` points).
const CC_MAX_LEVEL: usize = 12;
/// Highest Gauss level (`level + 1` points).
const GAUSS_MAX_LEVEL: usize = 199;

impl RuleKind {
    /// Human-readable name.
    pub fn name(&self) -> &'static str {
        match self {
            RuleKind::GenzKeister => "Genz-Keister",
            RuleKind::ClenshawCurtis => "Clenshaw-Curtis",
            RuleKind::GaussPatterson => "Gauss-Patterson",
            RuleKind::GaussLegendre => "Gauss-Legendre",
            RuleKind::GaussHermite => "Gauss-Hermite",
            RuleKind::Gauss(Family::Laguerre { .. }) => "Gauss-Laguerre",
            RuleKind::Gauss(Family::Jacobi { .. }) => "Gauss-Jacobi",
            RuleKind::Gauss(Family::Hermite) => "Gauss-Hermite",
            RuleKind::Gauss(Family::Legendre) => "Gauss-Legendre",
        }
    }

    /// The germ's orthonormal family: Hermite (normal germ), Legendre (uniform germ) or the
    /// family of a [`RuleKind::Gauss`] rule.
    pub fn family(&self) -> Family {
        match self {
            RuleKind::GenzKeister | RuleKind::GaussHermite => Family::Hermite,
            RuleKind::Gauss(f) => *f,
            _ => Family::Legendre,
        }
    }

    /// Whether the nodes of level `l` are among those of level `l + 1`.
    pub fn is_nested(&self) -> bool {
        matches!(
            self,
            RuleKind::GenzKeister | RuleKind::ClenshawCurtis | RuleKind::GaussPatterson
        )
    }

    /// Highest level available.
    pub fn max_level(&self) -> usize {
        match self {
            RuleKind::GenzKeister => GK_POINTS.len() - 1,
            RuleKind::ClenshawCurtis => CC_MAX_LEVEL,
            RuleKind::GaussPatterson => GP_MAX_LEVEL,
            RuleKind::GaussLegendre | RuleKind::GaussHermite | RuleKind::Gauss(_) => {
                GAUSS_MAX_LEVEL
            }
        }
    }

    fn check(&self, level: usize) -> Result<(), RuleError> {
        if level > self.max_level() {
            Err(RuleError::LevelTooHigh {
                rule: self.name(),
                level,
                max: self.max_level(),
            })
        } else {
            Ok(())
        }
    }

    /// Number of nodes at `level`.
    pub fn points(&self, level: usize) -> Result<usize, RuleError> {
        self.check(level)?;
        Ok(match self {
            RuleKind::GenzKeister => GK_POINTS[level],
            RuleKind::ClenshawCurtis => {
                if level == 0 {
                    1
                } else {
                    (1 << level) + 1
                }
            }
            RuleKind::GaussPatterson => (1 << (level + 1)) - 1,
            RuleKind::GaussLegendre | RuleKind::GaussHermite | RuleKind::Gauss(_) => level + 1,
        })
    }

    /// Degree of polynomial exactness at `level`.
    pub fn exactness(&self, level: usize) -> Result<usize, RuleError> {
        self.check(level)?;
        Ok(match self {
            RuleKind::GenzKeister => GK_EXACTNESS[level],
            RuleKind::ClenshawCurtis => self.points(level)?,
            RuleKind::GaussPatterson => {
                if level == 0 {
                    1
                } else {
                    3 * (1 << level) - 1
                }
            }
            RuleKind::GaussLegendre | RuleKind::GaussHermite | RuleKind::Gauss(_) => 2 * level + 1,
        })
    }

    /// The table (level, points, exactness) for levels `0..=max_level`. Serves the tests.
    #[cfg(test)]
    pub(crate) fn table(&self, max_level: usize) -> Vec<LevelInfo> {
        (0..=max_level.min(self.max_level()))
            .map(|level| LevelInfo {
                level,
                points: self.points(level).unwrap_or(0),
                exactness: self.exactness(level).unwrap_or(0),
            })
            .collect()
    }

    /// The rule at `level`.
    pub fn rule(&self, level: usize) -> Result<Rule1d, RuleError> {
        self.check(level)?;
        let exactness = self.exactness(level)?;
        let (nodes, weights) = match self {
            RuleKind::GenzKeister => genz_keister_table(level),
            RuleKind::GaussPatterson => {
                let pts: Vec<usize> = (0..=GP_MAX_LEVEL).map(|l| (1 << (l + 1)) - 1).collect();
                nested_cache(&GP_CACHE, Family::Legendre, &pts)?[level].clone()
            }
            RuleKind::ClenshawCurtis => clenshaw_curtis(self.points(level)?),
            RuleKind::GaussLegendre | RuleKind::GaussHermite | RuleKind::Gauss(_) => self
                .family()
                .gauss(level + 1)
                .map_err(|e| RuleError::Extension {
                    old: 0,
                    new: level + 1,
                    why: e.to_string(),
                })?,
        };
        Ok(Rule1d {
            nodes,
            weights,
            exactness,
        })
    }
}

type NodesWeights = (Vec<f64>, Vec<f64>);
type Cache = OnceLock<Result<Vec<NodesWeights>, RuleError>>;
static GP_CACHE: Cache = OnceLock::new();

fn nested_cache<'a>(
    cache: &'a Cache,
    fam: Family,
    points: &[usize],
) -> Result<&'a Vec<NodesWeights>, RuleError> {
    cache
        .get_or_init(|| nested_family(fam, points))
        .as_ref()
        .map_err(Clone::clone)
}

/// Genz–Keister table for the weight `exp(-x^2)` (non-negative nodes, their weights),
/// levels 0..=4 (1, 3, 9, 19, 35 points).
const GK_TABLE: [(&[f64], &[f64]); 5] = [
    (&[0.0], &[1.7724538509055159]),
    (
        &[0.0, 1.2247448713915889],
        &[1.1816359006036772, 0.2954089751509193],
    ),
    (
        &[
            0.0,
            0.52403354748695763,
            1.2247448713915889,
            2.0232301911005157,
            2.959210779063838,
        ],
        &[
            0.45014700975378197,
            0.47869428549114124,
            0.16811892894767771,
            0.014173117873979098,
            1.6708826306882348e-4,
        ],
    ),
    (
        &[
            0.0,
            0.52403354748695763,
            0.87004089535290285,
            1.2247448713915889,
            1.8357079751751868,
            2.0232301911005157,
            2.2665132620567876,
            2.959210779063838,
            3.6677742159463378,
            4.4995993983103881,
        ],
        &[
            0.53788160700510168,
            0.36924643368920851,
            0.10838861955003017,
            0.11360729895748269,
            0.032055243099445879,
            -0.011232438489069229,
            5.1133174390883855e-3,
            1.0656589772852267e-4,
            1.0802767206624762e-6,
            1.5295717705322357e-9,
        ],
    ),
    (
        &[
            0.0,
            0.17606414208200893,
            0.52403354748695763,
            0.87004089535290285,
            1.2247448713915889,
            1.5794121348467671,
            1.8357079751751868,
            2.0232301911005157,
            2.2665132620567876,
            2.5705583765842968,
            2.959210779063838,
            3.3491639537131945,
            3.6677742159463378,
            4.0292201405043713,
            4.4995993983103881,
            5.036089944473094,
            5.6432578578857449,
            6.3759392709822356,
        ],
        &[
            9.1262675363737921e-4,
            0.33988595585585218,
            0.26244871488784277,
            0.16371221555735804,
            0.080245518147390893,
            0.027780508908535097,
            5.592882891146918e-3,
            4.0967527720344047e-3,
            1.4515580425155904e-3,
            4.878539930444377e-4,
            6.3328620805617891e-5,
            4.8462799737020461e-6,
            4.3737818040926989e-7,
            3.7920222392319532e-8,
            8.1553721816916897e-10,
            5.4896836948499462e-12,
            9.6599466278563243e-15,
            1.8684014894510604e-18,
        ],
    ),
];

/// Genz–Keister rule at `level` (checked), probabilists' nodes, probability weights.
fn genz_keister_table(level: usize) -> NodesWeights {
    let (x, w) = GK_TABLE[level];
    let s2 = std::f64::consts::SQRT_2;
    let sp = std::f64::consts::PI.sqrt();
    let h = x.len();
    let n = 2 * h - 1;
    let mut nodes = vec![0.0; n];
    let mut weights = vec![0.0; n];
    for i in 0..h {
        nodes[h - 1 + i] = s2 * x[i];
        nodes[h - 1 - i] = -s2 * x[i];
        weights[h - 1 + i] = w[i] / sp;
        weights[h - 1 - i] = w[i] / sp;
    }
    (nodes, weights)
}

/// All levels of a nested Kronrod–Patterson family starting from the one-point rule.
fn nested_family(fam: Family, points: &[usize]) -> Result<Vec<NodesWeights>, RuleError> {
    let mut out = vec![(vec![0.0], vec![1.0])];
    let mut nodes = vec![0.0];
    for &n in &points[1..] {
        let new = patterson_extension(fam, &nodes, n - nodes.len())?;
        nodes.extend(new);
        nodes.sort_by(f64::total_cmp);
        symmetrize_nodes(&mut nodes);
        let w = interpolatory_weights(fam, &nodes)?;
        out.push((nodes.clone(), w));
    }
    Ok(out)
}

/// The `m` new nodes of the Patterson extension of `old` for the germ of `fam`.
fn patterson_extension(fam: Family, old: &[f64], m: usize) -> Result<Vec<f64>, RuleError> {
    let n = old.len();
    let err = |why: String| RuleError::Extension {
        old: n,
        new: m,
        why,
    };
    // G[k][j] = E[p(T) phi_j(T) phi_k(T)], degree <= n + 2m - 1: exact with this Gauss rule.
    let gauss_n = (n + 2 * m) / 2 + 1;
    let (gx, gw) = fam.gauss(gauss_n).map_err(|e| err(e.to_string()))?;
    let mut g = DMatrix::<f64>::zeros(m, m + 1);
    let mut phi = vec![0.0; m + 1];
    for (&x, &w) in gx.iter().zip(&gw) {
        let p: f64 = old.iter().map(|xi| x - xi).product();
        fam.eval_all(x, &mut phi);
        for k in 0..m {
            for j in 0..=m {
                g[(k, j)] += w * p * phi[j] * phi[k];
            }
        }
    }
    let a = g.columns(0, m).into_owned();
    let rhs = -g.column(m).into_owned();
    let c = a
        .lu()
        .solve(&rhs)
        .ok_or_else(|| err("singular moment matrix".into()))?;
    let q = |t: f64| -> f64 {
        let mut v = vec![0.0; m + 1];
        fam.eval_all(t, &mut v);
        v[m] + (0..m).map(|j| c[j] * v[j]).sum::<f64>()
    };
    let grid: Vec<f64> = match fam {
        Family::Hermite => (0..=40_000).map(|k| -20.0 + 1e-3 * k as f64).collect(),
        _ => (0..=40_000)
            .rev()
            .map(|k| (std::f64::consts::PI * k as f64 / 40_000.0).cos())
            .collect(),
    };
    let mut roots = Vec::with_capacity(m);
    let mut prev = (grid[0], q(grid[0]));
    for &t in &grid[1..] {
        let qt = q(t);
        if qt == 0.0 {
            roots.push(t);
        } else if prev.1 != 0.0 && (qt < 0.0) != (prev.1 < 0.0) {
            roots.push(bisect(&q, prev.0, t, prev.1));
        }
        prev = (t, qt);
    }
    if roots.len() != m {
        return Err(err(format!(
            "found {} real roots, expected {m}",
            roots.len()
        )));
    }
    if roots
        .iter()
        .any(|r| old.iter().any(|o| (r - o).abs() < 1e-10))
    {
        return Err(err("a new node coincides with an old one".into()));
    }
    Ok(roots)
}

fn bisect(f: &impl Fn(f64) -> f64, mut a: f64, mut b: f64, mut fa: f64) -> f64 {
    for _ in 0..200 {
        let mid = 0.5 * (a + b);
        if mid <= a || mid >= b {
            break;
        }
        let fm = f(mid);
        if fm == 0.0 {
            return mid;
        }
        if (fm < 0.0) == (fa < 0.0) {
            a = mid;
            fa = fm;
        } else {
            b = mid;
        }
    }
    0.5 * (a + b)
}

/// Interpolatory weights of the symmetric `nodes` (ascending) for the symmetric germ of
/// `fam`: odd moments vanish by symmetry, so only the even conditions
/// `sum_i w_i phi_2k(x_i) = delta_k0` are solved, over the non-negative nodes (half the
/// size, better conditioned).
fn interpolatory_weights(fam: Family, nodes: &[f64]) -> Result<Vec<f64>, RuleError> {
    let n = nodes.len();
    let half: Vec<f64> = nodes[n / 2..].to_vec(); // centre (if odd) and positive nodes
    let h = half.len();
    let mut v = DMatrix::<f64>::zeros(h, h);
    let mut phi = vec![0.0; 2 * h];
    for (i, &x) in half.iter().enumerate() {
        fam.eval_all(x, &mut phi);
        let mult = if x == 0.0 { 1.0 } else { 2.0 };
        for k in 0..h {
            v[(k, i)] = mult * phi[2 * k];
        }
    }
    let mut e0 = DVector::<f64>::zeros(h);
    e0[0] = 1.0;
    let u = v.lu().solve(&e0).ok_or_else(|| RuleError::Extension {
        old: n,
        new: 0,
        why: "singular interpolation matrix".into(),
    })?;
    let mut w = vec![0.0; n];
    for (i, &ui) in u.iter().enumerate() {
        w[n / 2 + i] = ui;
        w[n - 1 - (n / 2 + i)] = ui;
    }
    Ok(w)
}

/// Clenshaw–Curtis rule with `n` points (n = 1 or odd) for U(-1, 1), weights summing to 1.
fn clenshaw_curtis(n: usize) -> NodesWeights {
    if n == 1 {
        return (vec![0.0], vec![1.0]);
    }
    let nn = n - 1;
    let pi = std::f64::consts::PI;
    let mut x: Vec<f64> = (0..n).map(|j| -(pi * j as f64 / nn as f64).cos()).collect();
    symmetrize_nodes(&mut x);
    let w: Vec<f64> = (0..n)
        .map(|j| {
            let c = if j == 0 || j == nn { 1.0 } else { 2.0 };
            let mut s = 0.0;
            for k in 1..=nn / 2 {
                let b = if 2 * k == nn { 1.0 } else { 2.0 };
                s += b / (4.0 * (k * k) as f64 - 1.0)
                    * (2.0 * pi * (k * j) as f64 / nn as f64).cos();
            }
            // Sum-to-2 weight halved for the probability measure.
            0.5 * c / nn as f64 * (1.0 - s)
        })
        .collect();
    (x, w)
}

#[cfg(test)]
pub(super) mod tests;
