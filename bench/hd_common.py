"""What the high-dimensional goals of bench/run.py (bench/hd_goals.py) share between
uq-driver and its peers: the analytic benchmarks in numpy, their input laws, their exact or
high-accuracy references (computed here, independently of every tool compared), the
scrambled Sobol' designs the peers use, and the error measures of the goals.

Each benchmark's input law is given per input as ("uniform", low, high), ("normal", mean,
std) or ("lognormal", mu, sigma) (ln x ~ N(mu, sigma²)); its germ is U(-1, 1) for a uniform
input and N(0, 1) for the other two (a lognormal input through its isoprobabilistic map).
"""
import math
import warnings

import numpy as np
from scipy.special import ndtri
from scipy.stats import qmc

# ------------------------------------------------------------------ the benchmarks

ISHIGAMI_A, ISHIGAMI_B = 7.0, 0.1
G_A = (0.0, 1.0, 4.5, 9.0, 99.0, 99.0, 99.0, 99.0)
BOREHOLE_NAMES = ("rw", "r", "Tu", "Hu", "Tl", "Hl", "L", "Kw")
BOREHOLE_LO = (63070.0, 990.0, 63.1, 700.0, 1120.0, 9855.0)
BOREHOLE_HI = (115600.0, 1110.0, 116.0, 820.0, 1680.0, 12045.0)
RW = (0.10, 0.0161812)      # rw ~ N(0.10, 0.0161812²) m
LN_R = (7.71, 1.0056)       # ln r ~ N(7.71, 1.0056²), r in m

LAWS = {
    "ishigami": [(f"x{i}", ("uniform", -math.pi, math.pi)) for i in (1, 2, 3)],
    "borehole": [("rw", ("normal",) + RW), ("r", ("lognormal",) + LN_R)]
    + [(n, ("uniform", lo, hi)) for n, lo, hi in zip(BOREHOLE_NAMES[2:], BOREHOLE_LO,
                                                      BOREHOLE_HI)],
    "gfunction": [(f"x{i}", ("uniform", 0.0, 1.0)) for i in range(1, 9)],
}
FUNCTION_ID = {"ishigami": 1, "borehole": 2, "gfunction": 3}


def ishigami(x):
    a, b = ISHIGAMI_A, ISHIGAMI_B
    return np.sin(x[:, 0]) + a * np.sin(x[:, 1]) ** 2 + b * x[:, 2] ** 4 * np.sin(x[:, 0])


def borehole(x):
    rw, r, tu, hu, tl, hl, length, kw = x.T
    lnr = np.log(r / rw)
    return 2 * np.pi * tu * (hu - hl) / (
        lnr * (1 + 2 * length * tu / (lnr * rw ** 2 * kw) + tu / tl))


def gfunction(x):
    a = np.array(G_A)
    return np.prod((np.abs(4 * x - 2) + a) / (1 + a), axis=1)


FUNCTIONS = {"ishigami": ishigami, "borehole": borehole, "gfunction": gfunction}


def germ_kinds(case):
    """'uniform' (germ U(-1, 1)) or 'normal' (germ N(0, 1)) per input."""
    return ["uniform" if law[0] == "uniform" else "normal" for _, law in LAWS[case]]


def germ_to_physical(case, z):
    """Physical inputs (n × d) from germs z (n × d)."""
    x = np.empty_like(z)
    for j, (_, law) in enumerate(LAWS[case]):
        if law[0] == "uniform":
            x[:, j] = law[1] + (law[2] - law[1]) * 0.5 * (z[:, j] + 1)
        elif law[0] == "normal":
            x[:, j] = law[1] + law[2] * z[:, j]
        else:
            x[:, j] = np.exp(law[1] + law[2] * z[:, j])
    return x


def unit_to_germ(case, u):
    """Germs from points u in the unit cube (quantile of each germ)."""
    z = np.empty_like(u)
    for j, kind in enumerate(germ_kinds(case)):
        z[:, j] = 2 * u[:, j] - 1 if kind == "uniform" else ndtri(u[:, j])
    return z


def sobol_unit(d, n, seed):
    """The first n points of an Owen-scrambled Sobol' sequence (scipy, seeded)."""
    with warnings.catch_warnings():  # scipy warns when n is not a power of 2
        warnings.simplefilter("ignore", UserWarning)
        return qmc.Sobol(d, scramble=True, seed=seed).random(n)


# ------------------------------------------------------------------ references

def ishigami_exact():
    a, b, pi = ISHIGAMI_A, ISHIGAMI_B, math.pi
    v1 = 0.5 * (1 + b * pi ** 4 / 5) ** 2
    v2 = a * a / 8
    v13 = b * b * pi ** 8 * (1 / 18 - 1 / 50)
    v = a * a / 8 + b * pi ** 4 / 5 + b * b * pi ** 8 / 18 + 0.5
    return {"mean": a / 2, "std": math.sqrt(v), "first": [v1 / v, v2 / v, 0.0],
            "total": [(v1 + v13) / v, v2 / v, v13 / v]}


def gfunction_exact():
    vi = [1 / (3 * (1 + a) ** 2) for a in G_A]
    v = math.prod(1 + x for x in vi) - 1
    total = [vi[i] * math.prod(1 + vi[j] for j in range(8) if j != i) / v for i in range(8)]
    return {"mean": 1.0, "std": math.sqrt(v), "first": [x / v for x in vi], "total": total}


def borehole_reference(mc_samples=10 ** 6, rqmc_log2=20, rqmc_replicates=8):
    """Mean and Std of the borehole function: plain Monte Carlo of `mc_samples` points
    (numpy default_rng(0)) with its standard errors, and the more accurate randomized QMC
    estimate (rqmc_replicates Owen-scramblings of 2^rqmc_log2 Sobol' points, seeds 0..R-1)
    with the standard error from the spread of the replicates. Returns a dict."""
    f = borehole
    rng = np.random.default_rng(0)
    z = np.column_stack([rng.standard_normal(mc_samples), rng.standard_normal(mc_samples)]
                        + [rng.uniform(-1, 1, mc_samples) for _ in range(6)])
    y = f(germ_to_physical("borehole", z))
    n = len(y)
    mc_mean, mc_std = y.mean(), y.std(ddof=1)
    c = y - mc_mean
    mc_se_mean = mc_std / math.sqrt(n)
    mc_se_std = math.sqrt(max(np.mean(c ** 4) - mc_std ** 4, 0.0) / n) / (2 * mc_std)
    means, stds = [], []
    for r in range(rqmc_replicates):
        u = qmc.Sobol(8, scramble=True, seed=r).random_base2(rqmc_log2)
        yr = f(germ_to_physical("borehole", unit_to_germ("borehole", u)))
        means.append(yr.mean())
        stds.append(yr.std(ddof=1))
    means, stds = np.array(means), np.array(stds)
    return {"mean": float(means.mean()), "std": float(stds.mean()),
            "se_mean": float(means.std(ddof=1) / math.sqrt(len(means))),
            "se_std": float(stds.std(ddof=1) / math.sqrt(len(stds))),
            "rqmc_points": rqmc_replicates * 2 ** rqmc_log2,
            "mc_samples": n, "mc_mean": float(mc_mean), "mc_std": float(mc_std),
            "mc_se_mean": float(mc_se_mean), "mc_se_std": float(mc_se_std)}


# ------------------------------------------------------------------ errors and goals

def errors(case, est, ref):
    """The goal's error of an estimate {"mean", "std", "first", "total"} against ref:
    ishigami: max |S - exact| over first and total; borehole: (relative mean error,
    relative Std error); gfunction: max |S1 - exact|."""
    if case == "ishigami":
        return max(max(abs(a - b) for a, b in zip(est["first"], ref["first"])),
                   max(abs(a - b) for a, b in zip(est["total"], ref["total"])))
    if case == "borehole":
        return (abs(est["mean"] / ref["mean"] - 1), abs(est["std"] / ref["std"] - 1))
    if case == "gfunction":
        return max(abs(a - b) for a, b in zip(est["first"], ref["first"]))
    raise ValueError(case)


def meets(case, err):
    if case == "borehole":
        return err[0] <= 1e-3 and err[1] <= 1e-2
    return err <= (0.01 if case == "ishigami" else 0.02)


def fmt_err(case, err):
    if err is None:
        return "—"
    if case == "borehole":
        return f"{100 * err[0]:.3f} % / {100 * err[1]:.2f} %"
    return f"{err:.4f}" if err >= 1e-3 else f"{err:.1e}"


def worst(case, errs):
    """The worst of several errors (component-wise for the borehole)."""
    if case == "borehole":
        return (max(e[0] for e in errs), max(e[1] for e in errs))
    return max(errs)


# ------------------------------------------------------------------ chaos arithmetic

def sobol_from_chaos(alphas, coeffs):
    """Mean, Std, first-order and total Sobol' indices of an orthonormal chaos with
    multi-indices `alphas` (P × d) and coefficients `coeffs` (P)."""
    alphas, coeffs = np.asarray(alphas), np.asarray(coeffs, dtype=float)
    const = ~alphas.any(axis=1)
    mean = float(coeffs[const].sum())
    var_terms = np.where(const, 0.0, coeffs ** 2)
    var = float(var_terms.sum())
    d = alphas.shape[1]
    first, total = [], []
    for i in range(d):
        only_i = (alphas[:, i] > 0) & (np.delete(alphas, i, axis=1) == 0).all(axis=1)
        first.append(float(var_terms[only_i].sum() / var) if var > 0 else 0.0)
        total.append(float(var_terms[alphas[:, i] > 0].sum() / var) if var > 0 else 0.0)
    return {"mean": mean, "std": math.sqrt(var), "first": first, "total": total}


def loo_ols(a, y):
    """Least-squares coefficients of y on the columns of a and the relative leave-one-out
    error mean((y_i - ŷ_(-i))²) / Var y, from the hat matrix (no refits)."""
    q, r = np.linalg.qr(a)
    c = np.linalg.solve(r, q.T @ y)
    h = np.einsum("ij,ij->i", q, q)
    res = (y - a @ c) / np.maximum(1 - h, 1e-12)
    return c, float(np.mean(res ** 2) / max(np.var(y), 1e-300))
