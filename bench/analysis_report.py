"""`make bench`, analysis at the speed of the runs.

- For every built-in study (`--all-builtins`; by default every one whose runs take less than
  a few minutes on 2 cores), the wall time of the whole `uq-driver run` command beside the
  wall time of its runs, its analysis and its report (`timing` of summary.json): goal,
  analysis + report ≤ 20 % of the whole command.
- builtin:wheel-scm side by side with the same study written with OpenTURNS + fmpy and with
  chaospy + fmpy (bench/wheel_scm_openturns.py, bench/wheel_scm_chaospy.py: same nodes,
  chaos, statistics and files; their mean, Std and Sobol' indices are checked against
  uq-driver's): goal, the whole uq-driver command ≥ 3× faster than each.

Called by bench/run.py (`bench_analysis_report`), which owns the timing and printing helpers
passed in as `h`.
"""
import json
import sys
from pathlib import Path

GOAL_SHARE = 0.20
# Studies whose runs take at least LONG_RUNS_S: analysis + report at most GOAL_SHARE_LONG.
LONG_RUNS_S = 1.0
GOAL_SHARE_LONG = 0.10
GOAL_PEERS = 3.0
# Built-ins left out by default: their runs take 15 minutes to an hour or more on 2 cores
# (the bogie's 20 000-sample Latin hypercube, alone or in paper-bogie; the 8-input
# vehicle-track's 5 000-sample reference; the ride-comfort study over many tracks; the full
# car's critical speed, 256 runs of 240 s; its running safety in curves, 200 runs of 15 s).
# They are in `make paper`.
LONG = ("bogie-lhs-20000", "paper-bogie", "vehicle-track-8d-lhs", "paper-vehicle-track-tracks",
        "vehicle-critical-speed", "vehicle-curve-safety")


def builtins(driver, h):
    _, _, out = h.run_cmd([str(driver), "list"])
    # Each study's name on a line of its own ("builtin:NAME"), its description indented below.
    return [line.removeprefix("builtin:") for line in out.splitlines()
            if line.startswith("builtin:")]


def timings(out_dir):
    """(runs, analysis, report) seconds of a study folder; a suite's are summed over its
    variants."""
    s = json.loads((out_dir / "summary.json").read_text())
    if "variants" in s and "suite" in s:
        parts = [timings(out_dir / v["folder"]) for v in s["variants"]]
        return tuple(sum(p[i] for p in parts) for i in range(3))
    t = s["timing"]
    return t["runs_s"], t["analysis_s"], t["report_s"]


def share_table(h, work, driver, all_builtins):
    sec = h.Section("Analysis and report against the whole command, every built-in study",
                    ["study", "whole command (s)", "runs (s)", "analysis (s)", "report (s)",
                     "analysis + report / whole"])
    names = builtins(driver, h)
    skipped = [n for n in names if n in LONG and not all_builtins]
    worst = (0.0, None)
    worst_long = (0.0, None)
    for name in names:
        if name in skipped:
            continue
        out = work / "builtins" / name
        cmd = [str(driver), "run", f"builtin:{name}", "--out", str(out), "--fresh"]
        # The best of up to 5 runs of a short study (one run of a study of 5 s or more),
        # with the stage times of that same run.
        best = None
        for _ in range(5):
            wall, _, _ = h.run_cmd(cmd)
            if best is None or wall < best[0]:
                best = (wall, timings(out))
            if wall >= 5.0:
                break
        wall, (runs, analysis, report) = best
        share = (analysis + report) / wall
        worst = max(worst, (share, name), key=lambda x: x[0])
        if runs >= LONG_RUNS_S:
            worst_long = max(worst_long, (share, name), key=lambda x: x[0])
        sec.row(name, h.fmt_s(wall), h.fmt_s(runs), h.fmt_s(analysis), h.fmt_s(report),
                f"{100 * share:.1f} %")
    sec.cmd(f"target/release/uq-driver run builtin:NAME --out {h.rel(work / 'builtins')}/NAME "
            f"--fresh   # for NAME in `uq-driver list`")
    sec.note("Whole command: the wall time of the process, measured here (the best of 5 "
             "for a study that takes under 5 s). Runs, analysis and report: `timing` in the "
             "study's summary.json of that same run (a suite: summed over its variants). The rest of the command is starting the process, reading the study, "
             "opening (unzipping) the FMU and hashing it.")
    sec.note("Where the share stays high, the analysis is large against runs of milliseconds "
             "by construction. wheel-scm, wheel-sgm and wheel-sparse run 36-65 Wheel runs (or "
             "one Galerkin solve) of a few ms in all, then take 4 000 draws of the chaos at "
             "each of 501 times (exact quantiles at every time, densities at 150): about 2 "
             "million values. wheel-pce-lars fits a sparse LARS chaos with leave-one-out "
             "selection at each of the 501 times: that is its analysis (about 117 000 LARS "
             "steps). The quantile columns are public output (`<V>.csv`), so they are "
             "computed at every time, from the draws the study names (`series_samples`). "
             "For wheel-scm, 20 % of the command leaves about 4 ms for analysis and report; "
             "the exact quantiles of those 2 million values alone take longer (about 9 ms of CPU, "
             "over 4 ms even split over both cores: `cargo test --release -p uq-driver --lib -- --ignored "
             "column_timing --nocapture`), before the chaos is drawn, the densities taken "
             "or a file written. Fewer draws alone do not reach it either: wheel-scm with "
             "`series_samples` = 1024 and 512 (measured by hand, median of 9) still spends 43 % "
             "and 38 % in analysis and report, whose fixed part (about 15 files, densities, "
             "Sobol' indices, the heat map) does not shrink with the draws. The goal is out of "
             "reach for these studies unless they publish less than they do.")
    if skipped:
        sec.note("Not run here (their runs take 15 minutes to an hour or more on 2 cores; "
                 "`make paper` runs them): " + ", ".join(skipped) +
                 ". `bench/run.py --all-builtins` runs them too.")
    share, name = worst
    long_share, long_name = worst_long
    sec.done(f"Largest share of analysis + report: {100 * share:.1f} % ({name}). Goal ≤ "
             f"{100 * GOAL_SHARE:.0f} % for every study run here: {h.goal(share <= GOAL_SHARE)}. "
             f"Among the studies whose runs take ≥ {LONG_RUNS_S:g} s: largest "
             f"{100 * long_share:.1f} % ({long_name}); goal ≤ {100 * GOAL_SHARE_LONG:.0f} %: "
             f"{h.goal(long_share <= GOAL_SHARE_LONG)}.")
    return sec


def peer_check(h, ours, theirs):
    """Largest differences of mean, Std and Sobol' indices over time between two folders."""
    import numpy as np
    a, b = h.read_csv_cols(ours / "q.csv"), h.read_csv_cols(theirs / "q.csv")
    sa, sb = h.read_csv_cols(ours / "q_sobol.csv"), h.read_csv_cols(theirs / "q_sobol.csv")
    d = {c: float(np.max(np.abs(a[c] - b[c]))) for c in ("mean", "std", "std_pce")}
    # The indices are undefined at t = 0 (no variance): compared from the first step on.
    d["sobol"] = max(float(np.nanmax(np.abs(sa[c][1:] - sb[c][1:])))
                     for c in ("S_K", "S_C", "ST_K", "ST_C"))
    return d


def peers(h, work, driver, repeats, checks):
    sec = h.Section("builtin:wheel-scm: uq-driver vs OpenTURNS + fmpy vs chaospy + fmpy",
                    ["tool", "whole command, best (s)", "median (s)", "runs alone, best (s)",
                     "uq-driver's whole command faster by"])
    fmu = h.fmu("Wheel")
    py = sys.executable
    tools = {
        "uq-driver": lambda out: [str(driver), "run", "builtin:wheel-scm", "--out", str(out),
                                  "--fresh"],
        "OpenTURNS + fmpy": lambda out: [py, "bench/wheel_scm_openturns.py", str(fmu), str(out)],
        "chaospy + fmpy": lambda out: [py, "bench/wheel_scm_chaospy.py", str(fmu), str(out)],
    }
    dirs = {"uq-driver": work / "peer-uq-driver", "OpenTURNS + fmpy": work / "peer-openturns",
            "chaospy + fmpy": work / "peer-chaospy"}
    walls = {t: [] for t in tools}
    runs = {t: [] for t in tools}
    for _ in range(repeats):
        for t, cmd in tools.items():  # round robin: other load hits all three alike
            wall, _, out = h.run_cmd(cmd(dirs[t]))
            walls[t].append(wall)
            if t == "uq-driver":
                runs[t].append(timings(dirs[t])[0])
            else:
                runs[t].append(json.loads(out.strip().splitlines()[-1])["runs_s"])
    ub = min(walls["uq-driver"])
    ratios = {}
    for t in tools:
        b, m = h.best_median(walls[t])
        ratio = b / ub
        ratios[t] = ratio
        sec.row(t, h.fmt_s(b), h.fmt_s(m), h.fmt_s(min(runs[t])),
                "–" if t == "uq-driver" else h.fmt_ratio(ratio))
    sec.cmd(f"target/release/uq-driver run builtin:wheel-scm --out {h.rel(dirs['uq-driver'])} "
            f"--fresh   # x{repeats}")
    sec.cmd(f".venv/bin/python bench/wheel_scm_openturns.py {h.rel(fmu)} "
            f"{h.rel(dirs['OpenTURNS + fmpy'])}   # x{repeats}")
    sec.cmd(f".venv/bin/python bench/wheel_scm_chaospy.py {h.rel(fmu)} "
            f"{h.rel(dirs['chaospy + fmpy'])}   # x{repeats}")
    sec.note("The same study three ways: 6 × 6 Gauss–Hermite nodes, the Wheel FMU run at each "
             "(uq-driver through the C ABI in parallel; the scripts through fmpy's FMU2Slave, "
             "one instance reset between points, fmpy's fastest loop), a total-order-5 Hermite "
             "chaos projected on the nodes, mean and Std over time, Sobol' indices over time, "
             "quantiles (1, 50, 99 %) at all 501 times and the PDF at 150 times on a 200-point "
             "grid from 4 000 draws of the chaos (binned Gaussian kernel densities in all "
             "three), and the CSV files; uq-driver also writes its plots and index.html. "
             "Whole command: the wall time of the process (for the scripts: Python start-up "
             "and imports included). Runs alone: uq-driver's `timing.runs_s`; the scripts' "
             "fmpy loop (extraction included).")
    for t in ("OpenTURNS + fmpy", "chaospy + fmpy"):
        d = peer_check(h, dirs["uq-driver"], dirs[t])
        ok = d["mean"] <= 1e-12 and d["std"] <= 1e-12 and d["sobol"] <= 1e-6
        checks.append((f"{t} vs uq-driver: mean, Std, Sobol'", max(d.values()), ok))
        sec.note(f"- Check, {t} vs uq-driver over time: max |Δ mean| {d['mean']:.1e}, "
                 f"|Δ Std| {d['std']:.1e}, |Δ Std of the chaos| {d['std_pce']:.1e}, "
                 f"|Δ Sobol' index| {d['sobol']:.1e} ({'OK' if ok else 'FAILED'}: ≤ 1e-12, "
                 f"1e-12, 1e-6).")
    worst = min(ratios["OpenTURNS + fmpy"], ratios["chaospy + fmpy"])
    sec.done(f"The whole uq-driver command is {h.fmt_ratio(ratios['OpenTURNS + fmpy'])} faster "
             f"than the OpenTURNS script and {h.fmt_ratio(ratios['chaospy + fmpy'])} faster "
             f"than the chaospy script (best of {repeats}). Goal ≥ {GOAL_PEERS:g}×: "
             f"{h.goal(worst >= GOAL_PEERS)}.")
    return sec


def bench(h, work, driver, repeats, checks, all_builtins=False):
    """The two sections: analysis at the speed of the runs (see the module's doc)."""
    try:
        import chaospy  # noqa: F401
        import openturns  # noqa: F401
    except ImportError as e:
        h.die(f"{e}: install bench/requirements.txt into the venv (`make bench` does)")
    work = Path(work)
    return [peers(h, work, driver, repeats, checks),
            share_table(h, work, driver, all_builtins)]
