"""`make bench`, the small-probability goals, runs counted, side by side with OpenTURNS.

Four limit states of 8 inputs, each at P = 1e-3, 1e-4 and 1e-6 (P(y > b)):

- linear: y = x1 + … + x8, xᵢ normal: exact P = Φ(−β), linear in standard normal space;
- product: y = x1 · … · x8, xᵢ lognormal: ln y is normal, exact P, linear in standard space;
- squares: y = x1² + … + x8², xᵢ standard normal: a χ² with 8 degrees of freedom (exact tail
  by scipy.stats.chi2), a sphere in standard space (no single design point);
- correlated lognormal sum: y = x1 + … + x8, xᵢ lognormal (mean 1, CoV 0.2 … 0.4) with a
  Gaussian copula (Pearson correlation 0.5 between neighbours x_i, x_i+1): no closed form; the
  reference is an importance-sampling integral in numpy written here (its standard error
  stated).

uq-driver runs the C test FMU `Functions` (function 5 linear, 6 squares, 7 product; built by
uq-driver/tests/fmus/build.py) with `kind = "form"`, `"sorm"`, `"importance_sampling"` (after
FORM, target CoV 5 %, at most 2 000 runs) and `"subset"` (1 500 samples per level, p0 = 0.1:
at most 9 600 runs down to 1e-6); OpenTURNS evaluates the same functions in numpy
(ot.PythonFunction, its calls counted) with ot.FORM / ot.SORM (AbdoRackwitz from the median
point, restarted from u = 0.5 where it fails there),
ot.ProbabilitySimulationAlgorithm with ot.ImportanceSamplingExperiment at FORM's standard
design point (same CoV target and budget) and ot.SubsetSampling (same samples per level).

Goals: FORM within 1 % of the exact P where the limit state is linear in standard space, with
≤ 20 runs per input; IS after FORM within 10 % with CoV ≤ 5 % and ≤ 2 000 runs; subset within
20 % with CoV ≤ 15 % and ≤ 10 000 runs at 1e-6; every printed 95 % interval of IS and subset
covering the exact value for ≥ 18 of 20 seeds (IS on the linear and the correlated case at
1e-4; subset on the linear and the correlated case at 1e-6 and the product at 1e-4).

Called by bench/run.py (`bench_reliability_goals`), which owns the timing and printing helpers
passed in as `h`.
"""
import json
import math
import time

import numpy as np
from scipy import stats
from scipy.special import ndtr, ndtri

D = 8
TARGETS = (1e-3, 1e-4, 1e-6)
FORM_RUNS_PER_INPUT = 20
FORM_TOL = 0.01
IS_TOL, IS_COV, IS_RUNS = 0.10, 0.05, 2000
SUBSET_TOL, SUBSET_COV, SUBSET_RUNS = 0.20, 0.15, 10000
SUBSET_N = 1500
SEEDS = tuple(range(1, 21))
COVERAGE_GOAL = 18
THREADS = 1

# ------------------------------------------------------------------ the cases

LIN_MEANS = np.full(D, 1.0)
LIN_STDS = np.linspace(0.5, 1.2, D)
PROD_S = np.linspace(0.10, 0.275, D)          # ln x_i ~ N(0, s_i²)
CORR_COV = np.linspace(0.2, 0.4, D)            # CoV of the lognormal x_i, mean 1
CORR_RHO = 0.5                                 # Pearson, between x_i and x_i+1
CORR_S = np.sqrt(np.log1p(CORR_COV ** 2))
CORR_M = -0.5 * CORR_S ** 2


def corr_normal_matrix():
    """The normal-space correlation of the Gaussian copula that gives the Pearson correlation
    CORR_RHO between neighbouring lognormals (closed form for lognormals)."""
    r = np.eye(D)
    for i in range(D - 1):
        s1, s2 = CORR_S[i], CORR_S[i + 1]
        rz = math.log1p(CORR_RHO * math.sqrt(math.expm1(s1 * s1) * math.expm1(s2 * s2))) / (s1 * s2)
        r[i, i + 1] = r[i + 1, i] = rz
    return r


CASES = {
    "linear": {"title": "linear: y = Σ xᵢ, 8 normal inputs", "function": 5,
               "laws": [("normal", m, s) for m, s in zip(LIN_MEANS, LIN_STDS)],
               "linear_in_u": True},
    "product": {"title": "product: y = Π xᵢ, 8 lognormal inputs", "function": 7,
                "laws": [("lognormal", 0.0, s) for s in PROD_S], "linear_in_u": True},
    "squares": {"title": "sum of squares: y = Σ xᵢ², 8 standard normal inputs", "function": 6,
                "laws": [("normal", 0.0, 1.0)] * D, "linear_in_u": False},
    "corr": {"title": "correlated lognormal sum: y = Σ xᵢ, 8 lognormal inputs, Gaussian copula",
             "function": 5,
             "laws": [("lognormal", m, s) for m, s in zip(CORR_M, CORR_S)],
             "linear_in_u": False, "correlated": True},
}


def y_of_x(case, x):
    if case == "product":
        return np.prod(x, axis=1)
    if case == "squares":
        return np.sum(x * x, axis=1)
    return np.sum(x, axis=1)


def x_of_u(case, u):
    """Physical values from independent standard normals (the Nataf map)."""
    laws = CASES[case]["laws"]
    z = u @ np.linalg.cholesky(corr_normal_matrix()).T if CASES[case].get("correlated") else u
    x = np.empty_like(z)
    for i, (kind, a, b) in enumerate(laws):
        x[:, i] = a + b * z[:, i] if kind == "normal" else np.exp(a + b * z[:, i])
    return x


def limit_and_exact(case, p):
    """(b, exact P(y > b), reference text) for the closed-form cases."""
    beta = -ndtri(p)
    if case == "linear":
        sd = math.sqrt(float((LIN_STDS ** 2).sum()))
        b = float(LIN_MEANS.sum()) + beta * sd
        return b, float(ndtr(-(b - LIN_MEANS.sum()) / sd))
    if case == "product":
        sd = math.sqrt(float((PROD_S ** 2).sum()))
        b = math.exp(beta * sd)
        return b, float(ndtr(-math.log(b) / sd))
    if case == "squares":
        b = float(stats.chi2.isf(p, D))
        return b, float(stats.chi2.sf(b, D))
    raise ValueError(case)


# ------------------------------------------------------------------ the correlated case's reference

def corr_design_point(b):
    """The most likely point of y = b in standard space: HLRF iterations with the exact
    gradient (y = Σ exp(mᵢ + sᵢ (L u)ᵢ), ∇y = Lᵀ (s ∘ x)), halving the step while |g|
    grows."""
    chol = np.linalg.cholesky(corr_normal_matrix())

    def g_and_grad(u):
        x = x_of_u("corr", u[None, :])[0]
        return b - x.sum(), -(chol.T @ (CORR_S * x))

    u = np.zeros(D)
    for _ in range(500):
        g, dg = g_and_grad(u)
        target = (dg @ u - g) / (dg @ dg) * dg
        step = 1.0
        while True:
            cand = u + step * (target - u)
            gc, _ = g_and_grad(cand)
            if abs(gc) <= abs(g) or abs(g) < 1e-12 * b or step < 1e-4:
                break
            step *= 0.5
        if np.linalg.norm(cand - u) < 1e-12 * (1 + np.linalg.norm(u)):
            u = cand
            break
        u = cand
    g, _ = g_and_grad(u)
    if abs(g) > 1e-9 * b:
        raise RuntimeError(f"design point of the correlated case not found (g = {g})")
    return u


def corr_is(b, n, rng, centre=None):
    """P(y > b) by importance sampling N(centre, I) in standard space: (p, standard error)."""
    c = corr_design_point(b) if centre is None else centre
    acc, acc2, done = 0.0, 0.0, 0
    while done < n:
        m = min(500_000, n - done)
        u = rng.standard_normal((m, D)) + c
        w = np.exp(-u @ c + 0.5 * c @ c) * (y_of_x("corr", x_of_u("corr", u)) > b)
        acc += w.sum()
        acc2 += (w * w).sum()
        done += m
    p = acc / n
    return p, math.sqrt(max(acc2 / n - p * p, 0.0) / n)


def corr_reference(p_target, n=2_000_000):
    """b with P(y > b) ≈ p_target (from a first IS sample), then P(y > b) by a second,
    independent IS sample of n points: (b, p, standard error)."""
    rng = np.random.default_rng(12345)
    # b from the FORM approximation, then one secant step with IS estimates
    sd_guess = 2.0
    b = D + (-ndtri(p_target)) * sd_guess
    for _ in range(4):
        c = corr_design_point(b)
        p, _ = corr_is(b, 200_000, rng, c)
        # ln P is nearly linear in b here: one finite-difference slope
        p2, _ = corr_is(b * 1.01, 200_000, rng, c)
        slope = (math.log(p2) - math.log(p)) / (0.01 * b)
        b += (math.log(p_target) - math.log(p)) / slope
        if abs(math.log(p / p_target)) < 0.02:
            break
    b = float(f"{b:.6g}")
    p, se = corr_is(b, n, np.random.default_rng(54321))
    return b, p, se


def corr_crude_check(b, n=4_000_000):
    """Crude Monte Carlo of P(y > b) (numpy, default_rng(7)): (p, standard error)."""
    rng = np.random.default_rng(7)
    hits, done = 0, 0
    while done < n:
        m = min(1_000_000, n - done)
        hits += int((y_of_x("corr", x_of_u("corr", rng.standard_normal((m, D)))) > b).sum())
        done += m
    p = hits / n
    return p, math.sqrt(p * (1 - p) / n)


# ------------------------------------------------------------------ uq-driver

def study_toml(fmu, case, name, seed, b, method):
    lines = [f'name = "{name}"', f'fmu = "{fmu}"', f"seed = {seed}", "[experiment]",
             "start = 0.0", "stop = 0.1", "step = 0.1", "[fixed]",
             f"function = {CASES[case]['function']}"]
    for i, (kind, a, s) in enumerate(CASES[case]["laws"]):
        lines += ["[[parameters]]", f'name = "x{i + 1}"']
        if kind == "normal":
            lines += [f"mean = {float(a)!r}", f"std = {float(s)!r}"]
        else:  # uq-driver takes the mean and Std of the lognormal x
            mean = math.exp(a + 0.5 * s * s)
            lines += ['distribution = "lognormal"', f"mean = {mean!r}",
                      f"std = {mean * math.sqrt(math.expm1(s * s))!r}"]
    if CASES[case].get("correlated"):
        for i in range(D - 1):
            lines += ["[[correlation]]", f'between = ["x{i + 1}", "x{i + 2}"]',
                      f"rho = {CORR_RHO!r}"]
    lines += ["[outputs]", 'variables = ["y"]', "[[qoi]]", 'kind = "final"', 'name = "Y"',
              'signal = "y"', f"limits = [{float(b)!r}]", "[method]", method]
    return "\n".join(lines) + "\n"


SUBSET_BIG_N = 5000  # once, on the linear case at 1e-6: the runs the CoV goal of subset takes
METHODS = {
    "FORM": 'kind = "form"',
    "SORM": 'kind = "sorm"',
    "IS": f'kind = "importance_sampling"\ntarget_cov = {IS_COV}\nmax_runs = {IS_RUNS}',
    "subset": f'kind = "subset"\nsamples_per_level = {SUBSET_N}\np0 = 0.1',
    "subset-big": f'kind = "subset"\nsamples_per_level = {SUBSET_BIG_N}\np0 = 0.1',
}
TABLE_METHODS = ("FORM", "SORM", "IS", "subset")


def run_driver(h, driver, work, fmu, case, name, seed, b, method):
    """One study: a result dict, or one with "error" when uq-driver refused or failed."""
    path = work / f"{name}.toml"
    path.write_text(study_toml(fmu, case, name, seed, b, METHODS[method]))
    out = work / name
    cmd = [str(driver), "run", str(path), "--out", str(out), "--fresh", "--threads",
           str(THREADS)]
    t0 = time.perf_counter()
    try:
        h.run_cmd(cmd)
    except h.BenchError as e:
        msg = str(e).strip().splitlines()
        err = next((line for line in reversed(msg) if line.strip()), "failed")
        return {"error": err[:200], "time": time.perf_counter() - t0}
    wall = time.perf_counter() - t0
    s = json.loads((out / "summary.json").read_text())
    r = s["quantities"]["Y"]["reliability"][0]
    rec = r.get("importance_sampling") or {}
    return {"p": r["p"], "ci": r["ci_95"], "cov": r["cov"], "beta": r["beta"],
            "runs": r["runs"], "time": wall, "warnings": r.get("warnings") or [],
            "model_runs": s["model_runs"], "is_runs": rec.get("runs")}


# ------------------------------------------------------------------ OpenTURNS

def ot_distribution(case):
    import openturns as ot
    margs = []
    for kind, a, s in CASES[case]["laws"]:
        margs.append(ot.Normal(float(a), float(s)) if kind == "normal"
                     else ot.LogNormal(float(a), float(s), 0.0))
    if CASES[case].get("correlated"):
        r = corr_normal_matrix()
        cm = ot.CorrelationMatrix(D)
        for i in range(D):
            for j in range(D):
                cm[i, j] = float(r[i, j])
        return ot.JointDistribution(margs, ot.NormalCopula(cm))
    return ot.JointDistribution(margs)


class Counted:
    """An ot.PythonFunction of the case's y (numpy, vectorised) that counts its points."""

    def __init__(self, case):
        import openturns as ot
        self.n = 0

        def fs(x):
            a = np.asarray(x)
            self.n += len(a)
            return y_of_x(case, a).reshape(-1, 1)
        self.f = ot.PythonFunction(D, 1, func_sample=fs)


def ot_event(case, b):
    import openturns as ot
    dist = ot_distribution(case)
    fn = Counted(case)
    vec = ot.CompositeRandomVector(fn.f, ot.RandomVector(dist))
    return ot.ThresholdEvent(vec, ot.Greater(), float(b)), dist, fn


def ot_form(case, b, sorm=False):
    """AbdoRackwitz from the median point u = 0 (as uq-driver's FORM); when it fails there,
    once more from u = (0.5, …, 0.5), every call counted."""
    import openturns as ot
    event, _, fn = ot_event(case, b)
    t0 = time.perf_counter()
    errors = []
    for start in (0.0, 0.5):
        try:
            solver = ot.AbdoRackwitz()
            solver.setStartingPoint(ot.Point(D, start))
            algo = (ot.SORM if sorm else ot.FORM)(solver, event)
            algo.run()
            res = algo.getResult()
            break
        except Exception as e:  # noqa: BLE001 (OpenTURNS raises plain exceptions)
            errors.append(str(e).splitlines()[0][:120])
    else:
        return {"error": "; ".join(errors), "time": time.perf_counter() - t0,
                "runs": fn.n}, None
    wall = time.perf_counter() - t0
    if sorm:
        try:
            p = res.getEventProbabilityTvedt()
            beta = res.getGeneralisedReliabilityIndexTvedt()
        except Exception as e:  # noqa: BLE001 (undefined for strongly curved limit states)
            return {"error": str(e).splitlines()[0][:160], "time": wall, "runs": fn.n}, None
    else:
        p, beta = res.getEventProbability(), res.getHasoferReliabilityIndex()
    return {"p": p, "ci": None, "cov": None, "beta": beta, "runs": fn.n, "time": wall,
                "restarted": bool(errors)}, res


def ot_is(case, b, seed):
    """FORM, then importance sampling at its standard design point; the runs of both."""
    import openturns as ot
    ot.RandomGenerator.SetSeed(seed)
    form, res = ot_form(case, b)
    if res is None:
        return form
    event, _, fn = ot_event(case, b)
    t0 = time.perf_counter()
    ustar = res.getStandardSpaceDesignPoint()
    exp = ot.ImportanceSamplingExperiment(ot.Normal(ustar, ot.CovarianceMatrix(D)))
    algo = ot.ProbabilitySimulationAlgorithm(ot.StandardEvent(event), exp)
    algo.setMaximumCoefficientOfVariation(IS_COV)
    algo.setBlockSize(100)
    algo.setMaximumOuterSampling(IS_RUNS // 100)
    algo.run()
    r = algo.getResult()
    wall = time.perf_counter() - t0 + form["time"]
    out = sim_result(r, fn.n + form["runs"], wall)
    out["restarted"] = form.get("restarted", False)
    return out


def ot_subset(case, b, seed, n=SUBSET_N):
    import openturns as ot
    ot.RandomGenerator.SetSeed(seed)
    event, _, fn = ot_event(case, b)
    t0 = time.perf_counter()
    algo = ot.SubsetSampling(event)
    algo.setConditionalProbability(0.1)
    algo.setBlockSize(100)
    algo.setMaximumOuterSampling(n // 100)
    algo.run()
    return sim_result(algo.getResult(), fn.n, time.perf_counter() - t0)


def sim_result(r, runs, wall):
    p = r.getProbabilityEstimate()
    ci = r.getProbabilityDistribution().computeBilateralConfidenceInterval(0.95)
    cov = r.getCoefficientOfVariation()
    return {"p": p, "ci": [ci.getLowerBound()[0], ci.getUpperBound()[0]], "cov": cov,
            "beta": -ndtri(p) if 0 < p < 1 else None, "runs": runs, "time": wall}


# ------------------------------------------------------------------ formatting

def fmt_p(p):
    return "—" if p is None else f"{p:.4g}"


def rel_err(r, exact):
    return None if r.get("p") is None else r["p"] / exact - 1


def covers(r, exact):
    if r.get("ci") is None:
        return None
    lo, hi = r["ci"]
    return lo <= exact <= hi


def row_cells(tool, method, r, exact):
    if "error" in r:
        return [method, tool, f"failed: {r['error']}", "—", "—", "—", "—",
                str(r.get("runs", "—")), f"{r['time']:.2f}"]
    e = rel_err(r, exact)
    cv = covers(r, exact)
    ci = "—" if r["ci"] is None else f"{r['ci'][0]:.3g}–{r['ci'][1]:.3g}"
    return [method, tool, fmt_p(r["p"]), f"{100 * e:+.2f} %",
            "—" if r["cov"] is None else f"{100 * r['cov']:.1f} %", ci,
            "—" if cv is None else ("yes" if cv else "**no**"), str(r["runs"]),
            f"{r['time']:.2f}"]


# ------------------------------------------------------------------ one case

def bench_case(h, driver, work, fmu, case, refs):
    cfg = CASES[case]
    sec = h.Section(f"Small probabilities: {cfg['title']}",
                    ["exact P", "method", "tool", "P", "rel. error", "CoV", "95 % interval",
                     "covers?", "runs", "time (s)"])
    verdicts, warned = {}, []
    for p_t in TARGETS:
        b, exact, _ = refs[p_t]
        tag = f"{case}-{p_t:.0e}"
        ud = {m: run_driver(h, driver, work, fmu, case, f"{tag}-{m}", 1, b, m)
              for m in TABLE_METHODS}
        otr = {"FORM": ot_form(case, b)[0], "SORM": ot_form(case, b, sorm=True)[0],
               "IS": ot_is(case, b, 1), "subset": ot_subset(case, b, 1)}
        rows = [(m, m) for m in TABLE_METHODS]
        if case == "linear" and p_t == 1e-6:
            ud["subset-big"] = run_driver(h, driver, work, fmu, case, f"{tag}-subset-big", 1,
                                          b, "subset-big")
            otr["subset-big"] = ot_subset(case, b, 1, SUBSET_BIG_N)
            rows.append(("subset-big", f"subset, {SUBSET_BIG_N} per level"))
        for m, label in rows:
            for tool, r in (("uq-driver", ud[m]), ("OpenTURNS", otr[m])):
                name = label if not (m == "SORM" and tool == "OpenTURNS") else "SORM (Tvedt)"
                if r.get("restarted"):
                    name += " ²"
                sec.row(f"{exact:.4g} (b = {b:.6g})", *row_cells(tool, name, r, exact))
            for w in ud[m].get("warnings", []):
                warned.append(f"{label} at P ≈ {p_t:.0e}: {w}")
        verdicts[p_t] = {"b": b, "exact": exact, "ud": ud, "ot": otr}
    if warned:
        sec.note("uq-driver's warnings (summary.json, printed too): " + " — ".join(warned))
    sec.cmd(f"target/release/uq-driver run {h.rel(work)}/{case}-P-M.toml --out "
            f"{h.rel(work)}/{case}-P-M --fresh --threads {THREADS}   # P = 1e-03, 1e-04, 1e-06; "
            f"M = {', '.join(TABLE_METHODS)}"
            + ("; and linear-1e-06-subset-big" if case == "linear" else ""))
    return sec, verdicts


def goal_checks(case, verdicts):
    """[(goal text, met?, detail)] for one case."""
    cfg = CASES[case]
    out = []
    if cfg["linear_in_u"]:
        worst = max(abs(rel_err(v["ud"]["FORM"], v["exact"]) or math.inf)
                    if "error" not in v["ud"]["FORM"] else math.inf for v in verdicts.values())
        runs = max(v["ud"]["FORM"].get("runs") or 0 for v in verdicts.values())
        ok = worst <= FORM_TOL and runs <= FORM_RUNS_PER_INPUT * D
        out.append((f"FORM within {100 * FORM_TOL:.0f} % with ≤ {FORM_RUNS_PER_INPUT * D} runs",
                    ok, f"worst error {100 * worst:.2g} %, at most {runs} runs"))
    errs, covs, runs, fails, need, form_runs = [], [], [], 0, [], []
    for v in verdicts.values():
        r = v["ud"]["IS"]
        if "error" in r:
            fails += 1
            continue
        errs.append(abs(rel_err(r, v["exact"])))
        covs.append(r["cov"])
        runs.append(r["is_runs"])
        form_runs.append(r["runs"] - r["is_runs"])
        # IS's variance falls as 1/n: the runs at which its CoV would reach the target
        need.append(r["is_runs"] * (r["cov"] / IS_COV) ** 2)
    ok = (not fails and max(errs) <= IS_TOL and max(covs) <= IS_COV + 1e-12
          and max(runs) <= IS_RUNS)
    detail = ("failed at " + str(fails) + " of 3 P; " if fails else "")
    if errs:
        detail += (f"worst error {100 * max(errs):.1f} %, worst CoV {100 * max(covs):.1f} %, "
                   f"at most {max(runs)} IS runs after FORM's {min(form_runs)}–"
                   f"{max(form_runs)}")
        if max(covs) > IS_COV + 1e-12:
            detail += (f"; the CoV target would take about {max(need):.0f} IS runs "
                       f"(n·(CoV/{IS_COV:g})²)")
    out.append((f"IS after FORM within {100 * IS_TOL:.0f} %, CoV ≤ {100 * IS_COV:.0f} %, "
                f"≤ {IS_RUNS} runs", ok, detail))
    v = verdicts[1e-6]
    r = v["ud"]["subset"]
    if "error" in r:
        out.append(("subset at 1e-6", False, r["error"]))
    else:
        e = abs(rel_err(r, v["exact"]))
        ok = e <= SUBSET_TOL and r["cov"] <= SUBSET_COV and r["runs"] <= SUBSET_RUNS
        detail = f"error {100 * e:.1f} %, CoV {100 * r['cov']:.1f} %, {r['runs']} runs"
        big = v["ud"].get("subset-big")
        if big and "error" not in big:
            detail += (f"; with {SUBSET_BIG_N} per level: CoV {100 * big['cov']:.1f} %, error "
                       f"{100 * rel_err(big, v['exact']):+.1f} %, {big['runs']} runs")
        out.append((f"subset at 1e-6 within {100 * SUBSET_TOL:.0f} %, CoV ≤ "
                    f"{100 * SUBSET_COV:.0f} %, ≤ {SUBSET_RUNS} runs", ok, detail))
    return out


# ------------------------------------------------------------------ coverage over seeds

COVERAGE = (("IS", "linear", 1e-4), ("IS", "corr", 1e-4), ("subset", "linear", 1e-6),
            ("subset", "product", 1e-4), ("subset", "corr", 1e-6))


def width(r):
    """hi / lo of a printed interval (infinite when it reaches 0)."""
    lo, hi = r["ci"]
    return hi / lo if lo > 0 else math.inf


def bench_coverage(h, driver, work, fmu, refs):
    sec = h.Section("Small probabilities: coverage of the printed 95 % intervals over 20 seeds",
                    ["method", "case", "exact P", "tool", "intervals covering", "median P",
                     "worst rel. error", "median CoV", "median interval width (hi / lo)",
                     "runs (median)", "time (s, all seeds)"])
    results = []
    for method, case, p_t in COVERAGE:
        b, exact, _ = refs[case][p_t]
        for tool in ("uq-driver", "OpenTURNS"):
            rs = []
            t0 = time.perf_counter()
            for seed in SEEDS:
                if tool == "uq-driver":
                    r = run_driver(h, driver, work, fmu, case, f"cov-{method}-{case}-{seed}",
                                   seed, b, method)
                else:
                    r = (ot_is if method == "IS" else ot_subset)(case, b, seed)
                rs.append(r)
            wall = time.perf_counter() - t0
            good = [r for r in rs if "error" not in r]
            n_cov = sum(bool(covers(r, exact)) for r in good)
            ps = [r["p"] for r in good]
            sec.row(method, CASES[case]["title"].split(":")[0], f"{exact:.4g}", tool,
                    f"{n_cov} / {len(SEEDS)}{' ✓' if n_cov >= COVERAGE_GOAL else ''}",
                    fmt_p(float(np.median(ps))) if ps else "—",
                    f"{100 * max(abs(p / exact - 1) for p in ps):.1f} %" if ps else "—",
                    f"{100 * float(np.median([r['cov'] for r in good])):.1f} %" if good else "—",
                    f"{float(np.median([width(r) for r in good])):.2f}" if good else "—",
                    f"{int(np.median([r['runs'] for r in good]))}" if good else "—",
                    f"{wall:.1f}")
            results.append((method, case, tool, n_cov))
    sec.cmd(f"target/release/uq-driver run {h.rel(work)}/cov-M-C-S.toml --out "
            f"{h.rel(work)}/cov-M-C-S --fresh --threads {THREADS}   # S = 1..20 (the study seed)")
    sec.note(f"Goal: the printed 95 % interval covers the exact (or reference) P for ≥ "
             f"{COVERAGE_GOAL} of {len(SEEDS)} seeds. uq-driver's seed is the study's `seed`; "
             f"OpenTURNS's is ot.RandomGenerator.SetSeed(seed), its interval "
             f"getProbabilityDistribution().computeBilateralConfidenceInterval(0.95) (normal). "
             f"For the correlated case the reference's own "
             f"standard error is well under 1 % of P (see its section), small beside the "
             f"intervals. With 20 seeds, a true 95 % interval covers ≥ 18 times with "
             f"probability 0.92. The interval's width (hi / lo, median over the seeds) "
             f"shows how the coverage is bought: uq-driver's subset interval is log-normal on "
             f"the CoV of fully correlated levels (its summary.json says \"conservative\"), "
             f"OpenTURNS's is normal on its CoV; both IS intervals are on the estimated CoV "
             f"(uq-driver log-normal, OpenTURNS normal).")
    ud = [(m, c, n) for m, c, tool, n in results if tool == "uq-driver"]
    met = all(n >= COVERAGE_GOAL for _, _, n in ud)
    sec.done("uq-driver's intervals cover the exact value in " +
             ", ".join(f"{n}/20 ({m}, {c})" for m, c, n in ud) +
             f"; goal ≥ {COVERAGE_GOAL}/20 in each: {h.goal(met)}. OpenTURNS: " +
             ", ".join(f"{n}/20 ({m}, {c})" for m, c, tool, n in results
                       if tool == "OpenTURNS") + ".")
    return sec, met


# ------------------------------------------------------------------ all

def ot_version():
    import openturns
    return openturns.__version__


def bench(h, work, driver, test_fmu_dir):
    """The sections: the summary first, then one per case, then the coverage."""
    work, fmu = h.functions_fmu(work, "reliability", test_fmu_dir)
    t_ref = time.perf_counter()
    refs, corr_text = {}, []
    for case in CASES:
        refs[case] = {}
        for p_t in TARGETS:
            if case == "corr":
                b, p, se = corr_reference(p_t)
                refs[case][p_t] = (b, p, se)
                text = f"b = {b:.6g}: P = {p:.5g} ± {se:.2g} ({100 * se / p:.2f} %)"
                if p_t == 1e-3:
                    pc, sc = corr_crude_check(b)
                    text += (f"; crude Monte Carlo check, 4·10⁶ points: {pc:.4g} ± {sc:.2g} "
                             f"({(pc - p) / math.hypot(sc, se):+.1f} standard errors)")
                corr_text.append(text)
            else:
                b, exact = limit_and_exact(case, p_t)
                refs[case][p_t] = (b, exact, 0.0)
    t_ref = time.perf_counter() - t_ref
    sections, checks, all_v = [], {}, {}
    for case in CASES:
        sec, verdicts = bench_case(h, driver, work, fmu, case, refs[case])
        all_v[case] = verdicts
        checks[case] = goal_checks(case, verdicts)
        notes = []
        if case == "corr":
            notes.append(
                "Reference (no closed form): importance sampling in numpy, written in "
                "bench/reliability_goals.py, independent of both tools: the design point of "
                "y = b in standard space by HLRF with the exact gradient, then 2·10⁶ points of N(u*, I) "
                "(default_rng(54321)); b chosen by earlier, separate IS runs so that P ≈ the "
                "target. " + "; ".join(corr_text) + f" ({t_ref:.0f} s). The copula's normal "
                "correlation is the closed-form Nataf value for lognormals, "
                "ln(1 + ρ·√((e^{s²ᵢ}−1)(e^{s²ⱼ}−1)))/(sᵢsⱼ), given to OpenTURNS's "
                "NormalCopula; uq-driver gets the Pearson ρ = 0.5 and solves for it itself.")
        elif case == "squares":
            notes.append("Exact: P = scipy.stats.chi2.sf(b, 8). The failure domain is the "
                         "outside of a sphere in standard space: every point of it is a design "
                         "point, FORM and IS around one point are not made for it (FORM's start, "
                         "the mean, is a stationary point of y); subset simulation is.")
        else:
            notes.append("Exact: P = Φ(−β) (the limit state is linear in standard normal space, "
                         "so FORM is exact up to its convergence tolerance).")
        notes.append(
            "uq-driver: whole commands (process start, FMU load, outputs and report included), "
            f"--threads {THREADS}, seed 1; its IS runs include FORM's. OpenTURNS "
            f"{ot_version()}: seconds of the algorithm in-process on a numpy function (no FMU), "
            "ot.RandomGenerator seed 1; its runs are the points given to the function, its IS "
            "runs include its FORM's. SORM: uq-driver's chosen value (`p`), OpenTURNS's Tvedt. "
            "covers?: whether the printed 95 % interval holds the exact (reference) P. ²: "
            "OpenTURNS's AbdoRackwitz failed from the median point u = 0 (\"the gradient of "
            "the level function is zero\" after its first step; the same with a "
            "SymbolicFunction) and was restarted from u = (0.5, …, 0.5), its calls of both "
            "searches counted.")
        for n in notes:
            sec.note(n)
        sec.done("; ".join(f"{g}: {h.goal(ok)} ({d})" for g, ok, d in checks[case]) + ".")
        sections.append(sec)
    cov_sec, cov_met = bench_coverage(h, driver, work, fmu, refs)
    sections.append(cov_sec)
    return [summary_section(h, checks, cov_met, sections, all_v)] + sections


def summary_section(h, checks, cov_met, sections, all_v):
    sec = h.Section("Small probabilities: the goals, uq-driver", ["case", "goal", "met?",
                                                                  "measured"])
    n, met = 0, 0
    for case, cs in checks.items():
        for g, ok, d in cs:
            sec.row(CASES[case]["title"].split(":")[0], g, h.goal(ok), d)
            n += 1
            met += ok
    sec.row("coverage", f"IS and subset intervals cover in ≥ {COVERAGE_GOAL}/20 seeds",
            h.goal(cov_met), "see the coverage section")
    def errs(case, m):
        return [rel_err(v["ud"][m], v["exact"]) for v in all_v[case].values()
                if "error" not in v["ud"][m]]

    def pct(xs):
        return f"{100 * min(xs):+.0f} … {100 * max(xs):+.0f} %"

    def orders(xs):
        return f"{min(-math.log10(1 + x) for x in xs):.1f}–{max(-math.log10(1 + x) for x in xs):.1f}"
    big = all_v["linear"][1e-6]["ud"]["subset-big"]
    big_ot = all_v["linear"][1e-6]["ot"]["subset-big"]
    is_cov = {c: max(v["ud"]["IS"]["cov"] for v in all_v[c].values()
                     if "error" not in v["ud"]["IS"]) for c in CASES}
    sec.note(
        "The sections below hold every figure, OpenTURNS's beside uq-driver's. Why goals are "
        "not met, from the figures: (1) subset simulation's CoV at 1e-6 is about "
        "√(m (1 − p0)(1 + γ) / (p0 N)) for m = 6 levels of N samples (γ ≈ 1–2, the "
        f"correlation of the Markov chains): with N = {SUBSET_N} per level (at most "
        f"{SUBSET_N + 6 * (SUBSET_N - SUBSET_N // 10)} runs) that is 25–30 %, the same for "
        f"OpenTURNS's SubsetSampling at the same N; with N = {SUBSET_BIG_N} (linear case, "
        f"1e-6) uq-driver's CoV is still {100 * big['cov']:.1f} % in {big['runs']} runs "
        f"(OpenTURNS {100 * big_ot['cov']:.1f} % in {big_ot['runs']}): the goal's ≤ 10 000 runs "
        "and CoV ≤ 15 % are not reachable together by subset simulation with p0 = 0.1 as "
        "designed. (2) Importance sampling centred at FORM's design point: 2 000 runs end at "
        f"a CoV of {100 * is_cov['linear']:.1f} % (linear) and {100 * is_cov['product']:.1f} % "
        "(product) at 1e-6, just above the 5 % target; where the limit state is curved in "
        f"standard space (the correlated lognormal sum, FORM {pct(errs('corr', 'FORM'))} off) "
        f"the weights spread and the CoV ends at up to {100 * is_cov['corr']:.1f} %; on the "
        "sum of squares (a sphere in standard space: every direction is a design point) IS "
        f"around one point samples a sliver of the failure domain and is {pct(errs('squares', 'IS'))} "
        "off, with intervals that miss the exact value (uq-driver warns of a second design "
        "point and that the CoV target was not reached, and names subset simulation); FORM "
        f"alone is there {orders(errs('squares', 'FORM'))} orders of magnitude low, SORM "
        f"{orders(errs('squares', 'SORM'))} (curvature corrections at one point cannot "
        "represent a sphere).")
    sec.other = sum(s.other for s in sections) / len(sections)
    sec.done(f"uq-driver meets {met + cov_met} of {n + 1} goals.")
    return sec
