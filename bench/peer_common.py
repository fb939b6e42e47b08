"""What the two peer scripts (bench/wheel_scm_openturns.py, bench/wheel_scm_chaospy.py)
share: the study (uq-driver's builtin:wheel-scm), the fmpy loop that runs the FMU at the
collocation nodes, a binned Gaussian kernel density in numpy, and the output files.

The study: the paper's wheel, K ~ N(100, 10²) N/m, C ~ N(20, 2²) N.s/m, 0–5 s every
0.01 s, output q; stochastic collocation on 6 × 6 Gauss–Hermite nodes, Hermite chaos of
total order 5. The statistics are those uq-driver reports with its default [analysis]:
mean and Std over time (quadrature), Std of the chaos, first-order and total Sobol'
indices over time, quantiles 1 %, 50 %, 99 % at every time and the PDF at 150 times on a
200-point grid, both from 4 000 draws of the chaos, written as CSV files.
"""
import json
import os
import shutil
import sys
import time

import numpy as np

K_MEAN, K_STD, C_MEAN, C_STD = 100.0, 10.0, 20.0, 2.0
STOP, STEP = 5.0, 0.01
NT = round(STOP / STEP) + 1
TIMES = np.array([STOP if i == NT - 1 else i * STEP for i in range(NT)])
NODES, ORDER = 6, 5
DRAWS = 4000
QUANTILES = (0.01, 0.5, 0.99)
PDF_TIMES, PDF_GRID = 150, 200


def run_wheel(fmu_path, points):
    """q(t) at every point (K, C): fmpy's fastest loop, one FMU2Slave instance reset between
    points. Returns (runs × times array, wall time of the loop including extraction)."""
    from fmpy import extract, read_model_description
    from fmpy.fmi2 import FMU2Slave
    t0 = time.perf_counter()
    md = read_model_description(fmu_path)
    vr = {v.name: v.valueReference for v in md.modelVariables}
    unzip = extract(fmu_path)
    out = np.empty((len(points), NT))
    try:
        s = FMU2Slave(guid=md.guid, unzipDirectory=unzip,
                      modelIdentifier=md.coSimulation.modelIdentifier, instanceName="peer")
        s.instantiate()
        kc, q = [vr["K"], vr["C"]], [vr["q"]]
        for i, (k, c) in enumerate(points):
            if i:
                s.reset()
            s.setReal(kc, [float(k), float(c)])
            s.setupExperiment(startTime=0.0)
            s.enterInitializationMode()
            s.exitInitializationMode()
            row = out[i]
            row[0] = s.getReal(q)[0]
            for j in range(1, NT):
                s.doStep(currentCommunicationPoint=TIMES[j - 1],
                         communicationStepSize=TIMES[j] - TIMES[j - 1])
                row[j] = s.getReal(q)[0]
        s.terminate()
        s.freeInstance()
    finally:
        shutil.rmtree(unzip, ignore_errors=True)
    return out, time.perf_counter() - t0


def thinned(n, most):
    """At most `most` evenly spaced indices of n, with the last (as uq-driver)."""
    if n <= most:
        return list(range(n))
    step = -(-n // most)
    idx = list(range(0, n, step))
    if idx[-1] != n - 1:
        idx.append(n - 1)
    return idx


def silverman(x):
    n = len(x)
    std = x.std(ddof=1)
    q25, q75 = np.quantile(x, [0.25, 0.75])
    spread = min(std, (q75 - q25) / 1.34) if q75 > q25 else std
    return 0.9 * spread * n ** -0.2 if spread > 0 else 1e-3 * max(abs(x.mean()), 1.0)


def kde_binned(x, grid, h):
    """Gaussian kernel density on the uniform `grid`: linear binning onto a lattice of
    spacing <= h / 8 and a convolution (the same algorithm as uq-driver's)."""
    step = grid[1] - grid[0]
    k = max(1, int(np.ceil(8 * step / h)))
    delta = step / k
    taps = int(np.ceil(8 * h / delta))
    origin = grid[0] - taps * delta
    m = (len(grid) - 1) * k + 1 + 2 * taps
    u = (x - origin) / delta
    u = u[(u >= 0) & (u <= m - 1)]
    j = np.floor(u).astype(int)
    f = u - j
    mass = np.bincount(j, 1 - f, minlength=m + 1) + np.bincount(j + 1, f, minlength=m + 1)
    kernel = np.exp(-0.5 * ((np.arange(-taps, taps + 1) * delta / h) ** 2)) / (
        np.sqrt(2 * np.pi) * h * len(x))
    dens = np.convolve(mass[:m], kernel, mode="valid")
    return dens[::k][:len(grid)]


def kde_cells(x, grid, h):
    """The density averaged over each grid cell, for a distribution narrower than the grid
    (as uq-driver): binning and convolution on a lattice h / 8 apart over the data, then the
    integral over each cell of the piecewise linear density."""
    step = grid[1] - grid[0]
    delta, taps = h / 8, 64
    origin = x.min() - taps * delta
    m = int(np.ceil((x.max() - x.min()) / delta)) + 2 * taps + 2
    u = (x - origin) / delta
    j = np.floor(u).astype(int)
    f = u - j
    mass = np.bincount(j, 1 - f, minlength=m + 1) + np.bincount(j + 1, f, minlength=m + 1)
    kernel = np.exp(-0.5 * ((np.arange(-taps, taps + 1) * delta / h) ** 2)) / (
        np.sqrt(2 * np.pi) * h * len(x))
    dens = np.convolve(np.pad(mass[:m], taps), kernel, mode="valid")
    lattice = origin + delta * np.arange(m)
    cum = np.concatenate([[0.0], np.cumsum(0.5 * (dens[1:] + dens[:-1]) * delta)])
    edges = np.concatenate([grid - 0.5 * step, [grid[-1] + 0.5 * step]])
    return np.diff(np.interp(edges, lattice, cum)) / step


def pdf_evolution(draws):
    """(times, grid, density[time][grid]) from draws × times, as uq-driver's defaults."""
    picked = thinned(NT, PDF_TIMES)
    lo, hi = draws[:, picked].min(), draws[:, picked].max()
    pad = 0.05 * max(hi - lo, 1e-12 * max(abs(hi), 1.0))
    grid = np.linspace(lo - pad, hi + pad, PDF_GRID)
    dens = []
    for k in picked:
        col = draws[:, k]
        if col.max() - col.min() <= 1e-9 * max(abs(lo), abs(hi)):
            dens.append(np.full(PDF_GRID, np.nan))
        else:
            h = silverman(col)
            step = grid[1] - grid[0]
            dens.append(kde_cells(col, grid, h) if h < 2 * step else kde_binned(col, grid, h))
    return TIMES[picked], grid, np.array(dens)


def quadrature_moments(weights, y):
    """Mean and Std over time of the runs `y` (runs × times) with the quadrature `weights`."""
    w = np.asarray(weights)
    mean = w @ y
    return mean, np.sqrt(np.maximum(w @ (y - mean) ** 2, 0.0))


def write_outputs(out_dir, mean, std, std_chaos, draws, s1, st):
    """The CSV files of uq-driver, the quantiles and PDFs over time from `draws` (draws × times)
    of the chaos."""
    quantiles = np.quantile(draws, QUANTILES, axis=0)
    pdf = pdf_evolution(draws)
    os.makedirs(out_dir, exist_ok=True)
    cols = [TIMES, mean, std, mean - 3 * std, mean + 3 * std] + list(quantiles) + [std_chaos]
    head = "time,mean,std,lower_3sigma,upper_3sigma,q1,q50,q99,std_pce"
    np.savetxt(os.path.join(out_dir, "q.csv"), np.column_stack(cols), delimiter=",",
               header=head, comments="", fmt="%.17g")
    t, grid, dens = pdf
    rows = np.column_stack([np.repeat(t, len(grid)), np.tile(grid, len(t)), dens.ravel()])
    np.savetxt(os.path.join(out_dir, "q_pdf.csv"), rows, delimiter=",",
               header="time,x,density", comments="", fmt="%.17g")
    np.savetxt(os.path.join(out_dir, "q_sobol.csv"), np.column_stack([TIMES, s1.T, st.T]),
               delimiter=",", header="time,S_K,S_C,ST_K,ST_C", comments="", fmt="%.17g")


def report(started, runs_s, **extra):
    """The script's own timing, as one JSON line on standard output."""
    print(json.dumps({"runs_s": runs_s, "script_s": time.perf_counter() - started, **extra}))
    sys.stdout.flush()
