"""`make bench`, the 20-input chaos against OpenTURNS on the same points: analysis time.

The twenty-input Sobol' g-function (the Functions test FMU, `function = 8`, xᵢ ~ U(0, 1),
coefficients A20) through uq-driver's `pce_regression` (design = "qmc", 200 runs, order 10,
q_norm 0.5, sparse = true: LARS with the degree chosen by the corrected leave-one-out error,
plus its 5-fold cross-validation check); then OpenTURNS' FunctionalChaosAlgorithm with LARS
and the corrected leave-one-out error on the SAME 200 points and outputs (read from
uq-driver's points.csv and Y_samples.csv / `export --runs`), each total degree up to 10 with
the same stopping rule (bench/hd_openturns.py). Reported: uq-driver's analysis time
(summary.json `timing.analysis_s`, best of `repeats` re-analyses of the stored runs, and the
CPU seconds of that command) against OpenTURNS' fit time (wall and CPU of this process), and
the first-order Sobol' indices of both against the closed form. Also the series output y_t =
y (1 + t) (2 time columns, every column a chaos for the peer), analysed on principal
components (the default) and column by column.

Called by bench/run.py (`--only hd20`), which owns the timing and printing helpers passed in
as `h`.
"""
import json
import math
import resource
import shutil
import sys
import time
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent))

RUNS, ORDER, Q, SEED = 200, 10, 0.5, 1
DIM = 20
# Six inputs that matter, in decreasing order, and fourteen that barely do.
A20 = (0.0, 0.5, 1.0, 2.0, 4.5, 9.0) + (99.0,) * 14
STOP, STEP = 0.1, 0.1          # the series y_t: 2 columns (OpenTURNS fits each alone)
GOAL = "analysis time ≤ OpenTURNS' LARS fit on the same points"


def exact_first():
    """First-order Sobol' indices of the g-function with A20 (closed form, see
    uq-driver/tests/fmus/README.md): Vᵢ = 1/(3(1 + aᵢ)²), Var = ∏(1 + Vᵢ) − 1."""
    vi = [1 / (3 * (1 + a) ** 2) for a in A20]
    v = math.prod(1 + x for x in vi) - 1
    return [x / v for x in vi]


def study_toml(fmu, name, series, functional):
    lines = [f'name = "{name}"', f'fmu = "{fmu}"', f"seed = {SEED}", "[experiment]",
             "start = 0.0", f"stop = {STOP if series else 0.1}", f"step = {STEP}", "[fixed]",
             "function = 8"] + [f"a{i + 1} = {a!r}" for i, a in enumerate(A20)]
    for i in range(DIM):
        lines += ["[[parameters]]", f'name = "x{i + 1}"', 'distribution = "uniform"',
                  "low = 0.0", "high = 1.0"]
    lines += ["[outputs]", f'variables = ["{"y_t" if series else "y"}"]']
    if not series:
        lines += ["[[qoi]]", 'kind = "final"', 'name = "Y"', 'signal = "y"']
    lines += ["[method]", 'kind = "pce_regression"', 'design = "qmc"', f"samples = {RUNS}",
              f"order = {ORDER}", f"q_norm = {Q}", "sparse = true"]
    if functional:
        lines += ["[analysis]", f'functional = "{functional}"']
    return "\n".join(lines) + "\n"


def cpu_self():
    r = resource.getrusage(resource.RUSAGE_SELF)
    return r.ru_utime + r.ru_stime


def points(out):
    """The physical inputs (runs × 20) of a study folder, by run index."""
    pts = np.genfromtxt(out / "points.csv", delimiter=",", names=True, dtype=None,
                        encoding="utf-8")
    ok = [k for k, st in enumerate(pts["status"]) if st == "ok"]
    idx = np.atleast_1d(pts["index"])[ok].astype(int)
    x = np.column_stack([np.atleast_1d(pts[f"x{i + 1}"])[ok] for i in range(DIM)])
    return idx, x


def scalar_runs(out):
    idx, x = points(out)
    ys = np.genfromtxt(out / "Y_samples.csv", delimiter=",", names=True)
    by_run = dict(zip(np.atleast_1d(ys["run"]).astype(int), np.atleast_1d(ys["Y"])))
    return x, np.array([by_run[i] for i in idx])


def series_runs(h, driver, out):
    """(x, Y) with Y runs × columns, the series y_t of every run from `export --runs`."""
    h.run_cmd([str(driver), "export", str(out), "--runs"])
    csv = out / "runs" / "runs.csv"
    data = np.genfromtxt(csv, delimiter=",", names=True)
    runs = np.atleast_1d(data["run"]).astype(int)
    t = np.atleast_1d(data["time"])
    v = np.atleast_1d(data["y_t"])
    times = np.unique(t)
    idx, x = points(out)
    col = {tt: k for k, tt in enumerate(times)}
    y = np.full((len(idx), len(times)), np.nan)
    row = {i: k for k, i in enumerate(idx)}
    for r, tt, vv in zip(runs, t, v):
        if r in row:
            y[row[r], col[tt]] = vv
    if np.isnan(y).any():
        h.die(f"{out}: the exported runs miss values of y_t")
    return x, y


def reanalyse(h, driver, toml, out, repeats):
    """The analysis alone on the stored runs, `repeats` times: (analysis_s list, command CPU
    list, summary)."""
    secs, cpus = [], []
    for _ in range(repeats):
        _, cpu, _ = h.run_cmd([str(driver), "run", str(toml), "--out", str(out),
                               "--no-report"])
        s = json.loads((out / "summary.json").read_text())
        if s["runs_this_invocation"]:
            h.die(f"{out}: the analysis reran {s['runs_this_invocation']} runs")
        secs.append(s["timing"]["analysis_s"])
        cpus.append(cpu)
    return secs, cpus, s


def ot_fit(x, y):
    """OpenTURNS on every column of y (runs × columns): (wall s, CPU s, first-order
    indices of the first column)."""
    import hd_openturns
    laws = [("uniform", 0.0, 1.0)] * DIM
    c0, t0 = cpu_self(), time.perf_counter()
    ests = [hd_openturns.fit(laws, x, y[:, j], ORDER, Q) for j in range(y.shape[1])]
    return time.perf_counter() - t0, cpu_self() - c0, ests


def bench(h, work, driver, test_fmu_dir, repeats):
    work, fmu = h.functions_fmu(work, "hd20", test_fmu_dir)
    import openturns
    sec = h.Section(
        "20-input chaos: uq-driver's pce_regression against OpenTURNS' LARS on the same 200 "
        "points (g-function, order 10, q-norm 0.5)",
        ["output", "tool", "chaoses fitted", "analysis / fit, best (s)", "CPU (s)",
         "max |S1 − exact|"])
    exact = exact_first()
    cases = [("Y (scalar)", False, None), ("y_t, 2 times (pca)", True, "pca"),
             ("y_t, 2 times (columns)", True, "columns")]
    ratios = {}
    store = None
    for label, series, functional in cases:
        name = "g20-" + ("scalar" if not series else f"series-{functional}")
        toml = work / f"{name}.toml"
        toml.write_text(study_toml(fmu, name, series, functional))
        out = work / name
        if out.exists():
            shutil.rmtree(out)
        if series and store is not None:
            shutil.copytree(store, out / "store")  # the same runs: the analysis alone
        h.run_cmd([str(driver), "run", str(toml), "--out", str(out), "--no-report"])
        if series and store is None:
            store = out / "store"
        secs, cpus, s = reanalyse(h, driver, toml, out, repeats)
        sec.cmd(f"target/release/uq-driver run {h.rel(toml)} --out {h.rel(out)} --no-report"
                f"   # the runs, then the analysis alone x{repeats}")
        if series:
            x, y = series_runs(h, driver, out)
            fits = s["outputs"]["y_t"]["functional"]["fits"]
            sob = np.genfromtxt(out / "y_t_sobol.csv", delimiter=",", names=True)
            ud_first = [float(np.atleast_1d(sob[f"S_x{i + 1}"])[-1]) for i in range(DIM)]
        else:
            x, y = scalar_runs(out)
            y = y[:, None]
            fits = 1
            q = s["quantities"]["Y"]
            ud_first = [q["sobol"]["first"][f"x{i + 1}"] for i in range(DIM)]
        if len(x) != RUNS:
            h.die(f"{out}: {len(x)} runs, not {RUNS}")
        ud_err = max(abs(a - b) for a, b in zip(ud_first, exact))
        b = min(secs)
        k = secs.index(b)
        sec.row(label, "uq-driver pce_regression", fits, h.fmt_s(b), h.fmt_s(cpus[k]),
                f"{ud_err:.4f}")
        if series and functional == "columns":
            ot = ot_series  # the same columns and points as for the pca case
        else:
            ot = ot_fit(x, y)
            if series:
                ot_series = ot
        ot_wall, ot_cpu, ests = ot
        ot_err = max(abs(a - b) for a, b in zip(ests[-1]["first"], exact))
        sec.row(label, f"OpenTURNS {openturns.__version__} LARS", y.shape[1], h.fmt_s(ot_wall),
                h.fmt_s(ot_cpu), f"{ot_err:.4f}")
        ratios[label] = (ot_wall / b, ot_cpu / cpus[k])
    sec.note(
        f"uq-driver: the Functions test FMU (function = 8, a = {', '.join(f'{a:g}' for a in A20[:6])}, "
        f"99 × 14; xᵢ ~ U(0, 1)), `pce_regression` with design = \"qmc\" (seed {SEED}), "
        f"samples = {RUNS}, order = {ORDER}, q_norm = {Q}, sparse = true: hybrid LARS for each "
        f"total degree 1..{ORDER} (stopping after two degrees without improvement) plus the "
        f"5-fold cross-validation check of its leave-one-out error (5 more degree-adaptive "
        f"fits of one column). Its time is summary.json's timing.analysis_s of the command "
        f"rerun on the stored runs (best of {repeats}), the CPU that of the whole command. "
        f"OpenTURNS {openturns.__version__}: FunctionalChaosAlgorithm on the same points and "
        f"outputs (points.csv, Y_samples.csv, `uq-driver export --runs`), Legendre basis, "
        f"hyperbolic q-norm {Q}, LARS + corrected leave-one-out for each total degree up to "
        f"{ORDER} with the same stopping rule (bench/hd_openturns.py), one fit per column; "
        f"its time is the fits' wall time (and this process's CPU). The series case of "
        f"OpenTURNS is measured once and shown for both uq-driver fits. The S1 error is "
        f"the largest over the 20 inputs against the closed form (of the last time for the "
        f"series; y_t = y (1 + t) has y's indices).")
    met = ratios["Y (scalar)"][0] >= 1.0
    sec.done("OpenTURNS' fit time over uq-driver's analysis time (wall; CPU): "
             + ", ".join(f"{k} {h.fmt_ratio(w)}; {h.fmt_ratio(c)}"
                         for k, (w, c) in ratios.items())
             + f". Goal ({GOAL}, scalar): {h.goal(met)}.")
    return [sec]
