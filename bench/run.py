#!/usr/bin/env python3
"""`make bench`: measures railuq's FMUs and uq-driver, prints every result as a table row and
writes BENCHMARKS.md (command, machine, one section per measurement).

Run from the repository root by `make bench` (which first builds the release binaries, the
FMUs and the Python venv), or directly:

    .venv/bin/python bench/run.py [--repeats N] [--md FILE] [--work DIR] [--quick]
                                  [--only hd|hd20|vehicle|reliability|functional|python]

`--only hd` runs the high-dimensional goals alone (bench/hd_goals.py) into
target/bench/BENCHMARKS-hd.md, `--only vehicle` the full car's real-time factor alone into
target/bench/BENCHMARKS-vehicle.md, `--only reliability` the small-probability goals alone
(bench/reliability_goals.py: FORM, SORM, importance sampling, subset simulation beside
OpenTURNS; needs only uq-driver and a C compiler) into target/bench/BENCHMARKS-reliability.md,
`--only functional` the series fitted per column against on principal components alone into
target/bench/BENCHMARKS-functional.md, `--only python` the Python package against the command
line alone into target/bench/BENCHMARKS-python.md, `--only hd20` the 20-input chaos beside
OpenTURNS on the same points alone (bench/hd20.py; needs uq-driver and a C compiler) into
target/bench/BENCHMARKS-hd20.md.

Every comparison is measured side by side in this one run. Nothing here asserts a speed: the
goals set for the comparisons are reported as met or not met. The only hard failures are missing
prerequisites, a failing command, and a failed correctness check (fmpy vs uq-driver), which
invalidates the comparison: BENCHMARKS.md is still written, then the script exits with 1.

The machine has few cores and may be shared: repeated measurements are reported as best and
median, ratios use the best times (the least disturbed), and each section reports how much
CPU other processes used while it ran.
"""
import argparse
import csv
import datetime as dt
import hashlib
import json
import os
import platform
import resource
import shlex
import shutil
import statistics
import subprocess
import sys
import time
import tomllib
import zipfile
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
CARGO = os.environ.get("CARGO", "cargo")
DRIVER = Path(os.environ.get("RAILUQ_DRIVER", ROOT / "target" / "release" / "uq-driver"))
FMU_DIR = Path(os.environ.get("RAILUQ_FMU_DIR", ROOT / "target" / "fmu"))
LIB = ROOT / "target" / "release" / "librailuq.so"
MODELS = ("Wheel", "Bogie", "VehicleTrack", "Vehicle")

# The wheel study of the paper (section 3), as in the built-in studies.
M, Q0 = 10.0, 0.1
K_MEAN, K_STD, C_MEAN, C_STD = 100.0, 10.0, 20.0, 2.0
STOP, STEP = 5.0, 0.01
NT = round(STOP / STEP) + 1
REF_TIMES = (0.5, 1.0, 2.0, 3.0, 5.0)
CHECK_TOL = 1e-12

GOAL_FMPY = 50.0
GOAL_THREADS = 1.9
GOAL_RTF = 5.0
GOAL_VEHICLE_RTF = 20.0
GOAL_VT_DEFAULT = 40.0
GOAL_VT_FINE = 4.0
GOAL_VT_ACCURACY = 1e-12
GOAL_ISOLATE = 0.10
GOAL_PYTHON = 0.05


class BenchError(Exception):
    pass


def die(msg):
    raise BenchError(msg)


def rel(p):
    p = Path(p)
    try:
        return str(p.resolve().relative_to(ROOT))
    except ValueError:
        return str(p)


# ------------------------------------------------------------------ timing and load

def cpu_own():
    """CPU seconds of this process and its waited-for children."""
    s = resource.getrusage(resource.RUSAGE_SELF)
    c = resource.getrusage(resource.RUSAGE_CHILDREN)
    return s.ru_utime + s.ru_stime + c.ru_utime + c.ru_stime


def cpu_busy():
    """Busy CPU seconds of the whole machine (all cores), from /proc/stat."""
    with open("/proc/stat") as f:
        fields = [int(x) for x in f.readline().split()[1:]]
    idle = fields[3] + (fields[4] if len(fields) > 4 else 0)
    return (sum(fields[:8]) - idle) / os.sysconf("SC_CLK_TCK")


class LoadWatch:
    """How many cores other processes kept busy while a section ran."""

    def __init__(self):
        self.t0, self.busy0, self.own0 = time.perf_counter(), cpu_busy(), cpu_own()

    def other_cores(self):
        wall = time.perf_counter() - self.t0
        other = (cpu_busy() - self.busy0) - (cpu_own() - self.own0)
        return max(0.0, other / wall) if wall > 0 else 0.0


def functions_fmu(work, name, test_fmu_dir):
    """The folder `work/name` (created) and the path of the Functions test FMU, built into
    `test_fmu_dir` by uq-driver/tests/fmus/build.py."""
    work = Path(work) / name
    work.mkdir(parents=True, exist_ok=True)
    run_cmd([sys.executable, str(ROOT / "uq-driver/tests/fmus/build.py"), str(test_fmu_dir),
             "--only", "Functions"])
    return work, Path(test_fmu_dir).resolve() / "Functions.fmu"


def run_cmd(cmd, show_stderr=False):
    """Runs a command; returns (wall s, CPU s of the child, stdout). A failure is fatal."""
    r0 = resource.getrusage(resource.RUSAGE_CHILDREN)
    t0 = time.perf_counter()
    p = subprocess.run(cmd, cwd=ROOT, text=True, stdout=subprocess.PIPE,
                       stderr=None if show_stderr else subprocess.PIPE)
    wall = time.perf_counter() - t0
    r1 = resource.getrusage(resource.RUSAGE_CHILDREN)
    if p.returncode != 0:
        die(f"command failed (exit {p.returncode}): {shlex.join(map(str, cmd))}\n"
            f"{(p.stderr or '')[-3000:]}")
    cpu = (r1.ru_utime - r0.ru_utime) + (r1.ru_stime - r0.ru_stime)
    return wall, cpu, p.stdout or ""


def best_median(xs):
    return min(xs), statistics.median(xs)


def fmt_s(x):
    return f"{x:.3f}" if x < 100 else f"{x:.1f}"


def fmt_ratio(x):
    return f"{x:.2f}×" if x < 10 else f"{x:.1f}×" if x < 100 else f"{x:.0f}×"


def goal(ok):
    return "**met**" if ok else "**not met**"


# ------------------------------------------------------------------ printing

class Section:
    """One measurement: printed as it runs, then written to BENCHMARKS.md."""

    def __init__(self, title, header):
        self.title, self.header, self.rows = title, header, []
        self.commands, self.notes, self.verdict = [], [], ""
        self.watch = LoadWatch()
        self.other = None
        print(f"\n== {title}", flush=True)
        self._print_row(header)

    @staticmethod
    def _print_row(cells):
        print("  " + " | ".join(str(c) for c in cells), flush=True)

    def row(self, *cells):
        self.rows.append([str(c) for c in cells])
        self._print_row(cells)

    def cmd(self, c):
        self.commands.append(c)

    def note(self, text):
        self.notes.append(text)
        print(f"  {text}", flush=True)

    def done(self, verdict):
        if self.other is None:
            self.other = self.watch.other_cores()
        self.verdict = verdict
        print(f"  -> {verdict}", flush=True)
        print(f"  (other processes kept {self.other:.2f} cores busy meanwhile)", flush=True)

    def markdown(self):
        out = [f"## {self.title}", "", self.verdict, ""]
        def cells(r):
            return "| " + " | ".join(c.replace("|", "\\|") for c in r) + " |"
        out.append(cells(self.header))
        out.append("|" + "|".join("---" for _ in self.header) + "|")
        out += [cells(r) for r in self.rows]
        out.append("")
        for n in self.notes:
            out += [n, ""]
        if self.commands:
            out.append("Commands:")
            out.append("")
            out.append("```sh")
            out += self.commands
            out.append("```")
            out.append("")
        out += [f"Other processes kept {self.other:.2f} of {os.cpu_count()} cores busy on "
                f"average while this section ran.", ""]
        return "\n".join(out)


# ------------------------------------------------------------------ prerequisites, machine

def sha256(path):
    h = hashlib.sha256()
    with open(path, "rb") as f:
        for chunk in iter(lambda: f.read(1 << 20), b""):
            h.update(chunk)
    return h.hexdigest()


def fmu(name):
    return FMU_DIR / f"{name}.fmu"


def check_prerequisites(only=None):
    missing = []
    if not (DRIVER.is_file() and os.access(DRIVER, os.X_OK)):
        missing.append(f"{DRIVER} (build it: `make build`)")
    if only in ("reliability", "hd20"):  # uq-driver, the C test FMU (built here), OpenTURNS
        if missing:
            die("missing prerequisites:\n  " + "\n  ".join(missing))
        try:
            import fmpy  # noqa: F401
            import numpy  # noqa: F401
            import openturns  # noqa: F401
            import scipy  # noqa: F401
        except ImportError as e:
            die(f"{e}: run this script with the project venv (`make venv`, then "
                f".venv/bin/python; bench/requirements.txt)")
        return
    for m in MODELS:
        if not fmu(m).is_file():
            missing.append(f"{fmu(m)} (build it: `make fmu`)")
    if not LIB.is_file():
        missing.append(f"{LIB} (build it: `make build`)")
    if shutil.which(CARGO) is None:
        missing.append(f"cargo (`{CARGO}` is not on PATH)")
    if missing:
        die("missing prerequisites:\n  " + "\n  ".join(missing))
    cargo_toml = tomllib.loads((ROOT / "Cargo.toml").read_text())
    benches = [b for b in cargo_toml.get("bench", []) if b.get("name") == "fmi_step"]
    if not benches or benches[0].get("harness", True):
        die("Cargo.toml has no `[[bench]] name = \"fmi_step\"` with `harness = false`; add:\n\n"
            "[[bench]]\nname = \"fmi_step\"\nharness = false\n")
    if not (ROOT / "benches" / "fmi_step.rs").is_file():
        die("benches/fmi_step.rs is missing")
    try:
        import fmpy  # noqa: F401
        import numpy  # noqa: F401
    except ImportError as e:
        die(f"{e}: run this script with the project venv (`make venv`, then .venv/bin/python)")


def fmu_binary_sha(name):
    with zipfile.ZipFile(fmu(name)) as z:
        return hashlib.sha256(z.read(f"binaries/linux64/{name}.so")).hexdigest()


def machine():
    import fmpy
    import numpy as np
    info = {}
    with open("/proc/cpuinfo") as f:
        for line in f:
            if not line.strip():
                break  # the first processor is enough
            k, _, v = line.partition(":")
            info[k.strip()] = v.strip()
    cpu = info.get("model name", "unknown")
    if "cpu family" in info:
        cpu += f" (family {info['cpu family']}, model {info.get('model', '?')})"
    if "hypervisor" in info.get("flags", "").split():
        cpu += ", virtual machine"
    mem_kb = 0
    with open("/proc/meminfo") as f:
        for line in f:
            if line.startswith("MemTotal:"):
                mem_kb = int(line.split()[1])
    os_name = platform.system()
    try:
        with open("/etc/os-release") as f:
            for line in f:
                if line.startswith("PRETTY_NAME="):
                    os_name = line.split("=", 1)[1].strip().strip('"')
    except OSError:
        pass

    def out(cmd):
        try:
            return subprocess.run(cmd, cwd=ROOT, capture_output=True, text=True).stdout.strip()
        except OSError:
            return "?"
    commit = out(["git", "rev-parse", "--short", "HEAD"]) or "?"
    dirty = out(["git", "status", "--porcelain", "--untracked-files=no"])
    affinity = len(os.sched_getaffinity(0))
    cores = f"{os.cpu_count()} logical CPUs"
    if "cpu cores" in info and "siblings" in info:
        per_core = int(info["siblings"]) // max(1, int(info["cpu cores"]))
        cores += f" ({info['cpu cores']} cores × {per_core} thread per core, as reported)"
    with open("/proc/loadavg") as f:
        load = " ".join(f.read().split()[:3])
    return {
        "CPU": cpu,
        "cores": cores + ("" if affinity == os.cpu_count() else f", {affinity} usable here"),
        "RAM": f"{mem_kb / 1024 / 1024:.1f} GiB",
        "OS": f"{os_name}, kernel {platform.release()} ({platform.machine()})",
        "rustc": out(["rustc", "-V"]),
        "Python": platform.python_version(),
        "fmpy": fmpy.__version__,
        "numpy": np.__version__,
        "date": dt.datetime.now(dt.timezone.utc).strftime("%Y-%m-%d %H:%M UTC"),
        "commit": commit + (" with uncommitted changes" if dirty else ""),
        "load average at start": load,
    }


# ------------------------------------------------------------------ 1. fmi2DoStep

def bench_fmi_step(work, budget):
    sec = Section("1. Cost of one fmi2DoStep / fmi2GetReal through the C ABI",
                  ["model", "call", "communication step", "internal substeps",
                   "median ns/call", "best ns/call", "calls timed"])
    js = work / "fmi_step.json"
    vt_js = work / "vt_stepping.json"
    cmd = [CARGO, "bench", "--bench", "fmi_step", "--", "--json", str(js),
           "--budget", str(budget), "--vt-json", str(vt_js)]
    sec.cmd(f"cargo bench --bench fmi_step -- --json {rel(js)} --budget {budget} "
            f"--vt-json {rel(vt_js)}")
    run_cmd(cmd, show_stderr=True)  # cargo's progress goes to the terminal
    rows = json.loads(js.read_text())
    res = {}
    for r in rows:
        if r["call"] == "fmi2DoStep":
            what, sub = f"{r['step']:g} s", f"{r['substeps']} × {r['internal_step']:g} s"
        else:
            what, sub = "3 outputs: " + ", ".join(r["outputs"]), "–"
        sec.row(r["model"], r["call"], what, sub, f"{r['median_ns']:.0f}",
                f"{r['best_ns']:.0f}", r["calls"])
        res[(r["model"], r["call"])] = r
    lib_sha = sha256(LIB)
    fmu_sha = {m: fmu_binary_sha(m) for m in MODELS}
    same = all(s == lib_sha for s in fmu_sha.values())
    sec.note("Timed in batches with std::time::Instant: a Wheel episode is 500 steps (0–5 s), "
             "a Bogie episode the full ramp (45 000 steps, 0–450 s), a VehicleTrack episode "
             "500 steps (0–0.5 s); the instance is reset between episodes (not timed). "
             "fmi2GetReal is timed in batches of 20 000 calls.")
    if not same:
        sec.note("**Warning:** target/release/librailuq.so differs from the binary in the "
                 "FMUs (the library was rebuilt after `make fmu`): these per-call costs are of "
                 "the rebuilt library.")
    w = res[("Wheel", "fmi2DoStep")]
    sec.done(f"One Wheel communication step of 0.01 s (10 RK4 substeps) costs "
             f"{w['best_ns']:.0f} ns at best, {w['median_ns']:.0f} ns median, including the "
             f"FMI call overhead; no goal is set for this number.")
    return sec, res, same


# ------------------------------------------------------------------ 2. 1 000 wheel runs

def read_points(path):
    with open(path) as f:
        rows = list(csv.DictReader(f))
    if not rows or any(r.get("status") != "ok" for r in rows):
        die(f"{path}: expected only successful points")
    return [(float(r["K"]), float(r["C"])) for r in rows]


def read_csv_cols(path):
    import numpy as np
    with open(path) as f:
        rows = list(csv.reader(f))
    head = rows[0]
    data = np.array([[float(x) for x in r] for r in rows[1:]])
    return {h: data[:, i] for i, h in enumerate(head)}


def fmpy_simulate_loop(points):
    """What a typical user writes: one simulate_fmu call per point."""
    import numpy as np
    from fmpy import simulate_fmu
    path = str(fmu("Wheel"))
    out = np.empty((len(points), NT))
    t0 = time.perf_counter()
    for i, (k, c) in enumerate(points):
        r = simulate_fmu(path, start_values={"K": k, "C": c}, stop_time=STOP,
                         output_interval=STEP, output=["q"])
        out[i] = r["q"]
    wall = time.perf_counter() - t0
    times = r["time"]
    return wall, out, times


def fmpy_slave_loop(points):
    """The fast fmpy loop (bench/peer_common.py): extract once, one FMU2Slave instance,
    fmi2Reset between points. Returns (wall time, runs × times array of q)."""
    sys.path.insert(0, str(Path(__file__).resolve().parent))
    import peer_common
    out, wall = peer_common.run_wheel(str(fmu("Wheel")), points)
    return wall, out


def bench_wheel_1000(work, repeats, quick, checks):
    import numpy as np
    sec = Section("2. 1 000 wheel runs: uq-driver (1 thread) vs an fmpy loop",
                  ["runner", "wall time, best (s)", "median (s)", "repeats",
                   "uq-driver runs faster by"])
    out_dir = work / "lhs1000-t1"
    cmd = [str(DRIVER), "run", "builtin:wheel-lhs-1000", "--out", str(out_dir),
           "--threads", "1", "--fresh"]
    sec.cmd(f"target/release/uq-driver run builtin:wheel-lhs-1000 --out {rel(out_dir)} "
            f"--threads 1 --fresh   # x{repeats}")
    totals, runs = [], []
    for _ in range(repeats):
        wall, _, _ = run_cmd(cmd)
        summary = json.loads((out_dir / "summary.json").read_text())
        if summary["model_runs"] != 1000 or summary["threads"] != 1 or summary["failed_runs"]:
            die(f"{out_dir}/summary.json: unexpected runs/threads/failures")
        totals.append(wall)
        runs.append(summary["wall_time_s"])
    points = read_points(out_dir / "points.csv")
    qcsv = read_csv_cols(out_dir / "q.csv")
    if len(points) != 1000 or len(qcsv["time"]) != NT:
        die("uq-driver wrote an unexpected design or time grid")

    n_sim = 100 if quick else len(points)
    sec.cmd(f"# fmpy {n_sim} × simulate_fmu('Wheel.fmu', start_values={{'K': K, 'C': C}}, "
            f"stop_time=5, output_interval=0.01, output=['q']) over points.csv")
    sim_wall, sim_q, sim_t = fmpy_simulate_loop(points[:n_sim])
    if n_sim < len(points):
        sim_wall_1000 = sim_wall * len(points) / n_sim
    else:
        sim_wall_1000 = sim_wall
    sec.cmd(f"# fmpy extract once, one FMU2Slave, reset() + doStep/getReal per step, "
            f"x{repeats}")
    slave = [fmpy_slave_loop(points) for _ in range(repeats)]
    slave_walls = [w for w, _ in slave]
    slave_q = slave[-1][1]

    rb, rm = best_median(runs)
    tb, tm = best_median(totals)
    sb, sm = best_median(slave_walls)
    sec.row("uq-driver, the runs alone (`wall_time_s` of summary.json)", fmt_s(rb), fmt_s(rm),
            repeats, "–")
    sec.row("uq-driver, the whole command (runs + analysis + report)", fmt_s(tb), fmt_s(tm),
            repeats, "–")
    label = "fmpy `simulate_fmu` per point"
    if n_sim < len(points):
        label += f" ({n_sim} points, scaled to 1 000)"
    sec.row(label, fmt_s(sim_wall_1000), "–", 1,
            f"{fmt_ratio(sim_wall_1000 / rb)} (runs) / {fmt_ratio(sim_wall_1000 / tb)} (command)")
    sec.row("fmpy `FMU2Slave` reused, `reset()` between points", fmt_s(sb), fmt_s(sm), repeats,
            f"{fmt_ratio(sb / rb)} (runs) / {fmt_ratio(sb / tb)} (command)")

    # Correctness: the same runs give the same numbers.
    dt_max = float(np.max(np.abs(sim_t - qcsv["time"])))
    d_slave = float(np.max(np.abs(slave_q.mean(axis=0) - qcsv["mean"])))
    d_std = float(np.max(np.abs(slave_q.std(axis=0, ddof=1) - qcsv["std"])))
    d_traj = float(np.max(np.abs(sim_q - slave_q[:n_sim])))
    lines = [
        ("fmpy FMU2Slave loop: mean of q over the 1 000 runs vs uq-driver q.csv `mean`, "
         "max |Δ| over 501 times", d_slave),
        ("fmpy FMU2Slave loop: Std (ddof = 1) vs q.csv `std`, max |Δ|", d_std),
        (f"fmpy simulate_fmu vs FMU2Slave, every q of the {n_sim} trajectories, max |Δ|",
         d_traj),
        ("fmpy simulate_fmu time grid vs q.csv `time`, max |Δ|", dt_max),
    ]
    if n_sim == len(points):
        lines.insert(1, ("fmpy simulate_fmu loop: mean of q vs q.csv `mean`, max |Δ|",
                         float(np.max(np.abs(sim_q.mean(axis=0) - qcsv["mean"])))))
    for text, d in lines:
        ok = d <= CHECK_TOL
        checks.append((text, d, ok))
        sec.note(f"- Check: {text} = {d:.2e} (≤ {CHECK_TOL:g}: {'OK' if ok else 'FAILED'})")
    sec.note(f"The fmpy loops run exactly the 1 000 (K, C) points of `{rel(out_dir)}/points.csv` "
             f"(LHS, seed 42) for 0–5 s at step 0.01 and record q every step, as uq-driver "
             f"does. Ratios use the best times; both sides run on one thread.")
    ratio_sim, ratio_slave = sim_wall_1000 / rb, sb / rb
    sec.done(f"uq-driver (1 thread, the runs alone) is {fmt_ratio(ratio_sim)} faster than the "
             f"simulate_fmu loop and {fmt_ratio(ratio_slave)} faster than the reused-FMU2Slave "
             f"loop (whole command: {fmt_ratio(sim_wall_1000 / tb)} and "
             f"{fmt_ratio(sb / tb)}). Goal ≥ {GOAL_FMPY:g}×: {goal(ratio_sim >= GOAL_FMPY)} "
             f"against the simulate_fmu loop, {goal(ratio_slave >= GOAL_FMPY)} against the "
             f"reused-FMU2Slave loop.")
    return sec


# ------------------------------------------------------------------ 3. threads

def bench_threads(work, repeats):
    sec = Section("3. uq-driver on 2 threads vs 1 thread (builtin:wheel-lhs-10000)",
                  ["threads", "runs wall, best (s)", "runs median (s)",
                   "command wall, best (s)", "command median (s)", "CPU / command wall"])
    res = {1: ([], [], []), 2: ([], [], [])}
    for t in (1, 2):
        sec.cmd(f"target/release/uq-driver run builtin:wheel-lhs-10000 "
                f"--out {rel(work / f'lhs10000-t{t}')} --threads {t} --fresh   # x{repeats}")
    for _ in range(repeats):
        for t in (1, 2):  # alternate, so that slow phases of other load hit both
            out_dir = work / f"lhs10000-t{t}"
            wall, cpu, _ = run_cmd([str(DRIVER), "run", "builtin:wheel-lhs-10000", "--out",
                                    str(out_dir), "--threads", str(t), "--fresh"])
            s = json.loads((out_dir / "summary.json").read_text())
            if s["threads"] != t or s["model_runs"] != 10000 or s["failed_runs"]:
                die(f"{out_dir}/summary.json: unexpected threads/runs/failures")
            res[t][0].append(s["wall_time_s"])
            res[t][1].append(wall)
            res[t][2].append(cpu / wall)
    for t in (1, 2):
        rb, rm = best_median(res[t][0])
        cb, cm = best_median(res[t][1])
        sec.row(t, fmt_s(rb), fmt_s(rm), fmt_s(cb), fmt_s(cm),
                f"{statistics.median(res[t][2]):.2f}")
    same = all((work / "lhs10000-t1" / f).read_bytes() == (work / "lhs10000-t2" / f).read_bytes()
               for f in ("q.csv", "points.csv"))
    sec.note(f"Check: q.csv and points.csv are byte-identical for 1 and 2 threads: "
             f"{'OK' if same else 'FAILED'}.")
    runs_ratio = min(res[1][0]) / min(res[2][0])
    runs_ratio_med = statistics.median(res[1][0]) / statistics.median(res[2][0])
    cmd_ratio = min(res[1][1]) / min(res[2][1])
    sec.note(f"Speed-up 1 → 2 threads: runs {runs_ratio:.2f}× (best), {runs_ratio_med:.2f}× "
             f"(median); whole command {cmd_ratio:.2f}× (best). The command also analyses and "
             f"writes the report, partly on one thread.")
    sec.other = sec.watch.other_cores()
    busy = runs_ratio < GOAL_THREADS and sec.other > 0.25
    sec.done(f"Two threads run the 10 000 model runs {runs_ratio:.2f}× faster than one "
             f"(best times; {runs_ratio_med:.2f}× from the medians, which other load "
             f"disturbs more). Goal ≥ {GOAL_THREADS}×: {goal(runs_ratio >= GOAL_THREADS)}"
             + (f" on this run, while other processes kept {sec.other:.2f} of the "
                f"{os.cpu_count()} cores busy, taking CPU from the second thread" if busy
                else "") + ".")
    return sec, same


# ------------------------------------------------------------------ the Python package

PYTHON_RUN = ("import sys, railuq; railuq.builtin('wheel-lhs-10000').run(out=sys.argv[1], "
              "fresh=True, report=False, progress=False)")


def bench_python(work, repeats):
    """builtin:wheel-lhs-10000 from Python (railuq, the package `make wheel` installs into the
    venv) against the command line, both without the report; alternated."""
    sec = Section("3b. The Python package vs the command line (builtin:wheel-lhs-10000)",
                  ["path", "runs wall, best (s)", "runs median (s)", "command wall, best (s)",
                   "command median (s)"])
    py = [sys.executable, "-c", PYTHON_RUN]
    sec.cmd(f"target/release/uq-driver run builtin:wheel-lhs-10000 --out "
            f"{rel(work / 'lhs10000-cli')} --fresh --no-report   # x{repeats}")
    sec.cmd(f"python -c \"{PYTHON_RUN}\" {rel(work / 'lhs10000-py')}   # x{repeats}")
    if subprocess.run([sys.executable, "-c", "import railuq"], capture_output=True).returncode:
        sec.note("The railuq package is not installed in this venv (`make wheel` installs it).")
        sec.done("Not measured: railuq is not installed.")
        return sec
    res = {"cli": ([], []), "python": ([], [])}
    for _ in range(repeats):
        for path in ("cli", "python"):  # alternate, so that slow phases of other load hit both
            out_dir = work / f"lhs10000-{'py' if path == 'python' else 'cli'}"
            cmd = ([str(DRIVER), "run", "builtin:wheel-lhs-10000", "--out", str(out_dir),
                    "--fresh", "--no-report"] if path == "cli" else py + [str(out_dir)])
            wall, _cpu, _ = run_cmd(cmd)
            s = json.loads((out_dir / "summary.json").read_text())
            if s["model_runs"] != 10000 or s["failed_runs"]:
                die(f"{out_dir}/summary.json: unexpected runs/failures")
            res[path][0].append(s["wall_time_s"])
            res[path][1].append(wall)
    for path in ("cli", "python"):
        rb, rm = best_median(res[path][0])
        cb, cm = best_median(res[path][1])
        sec.row(path, fmt_s(rb), fmt_s(rm), fmt_s(cb), fmt_s(cm))
    same = all((work / "lhs10000-cli" / f).read_bytes() == (work / "lhs10000-py" / f).read_bytes()
               for f in ("q.csv", "points.csv"))
    sec.note(f"Check: q.csv and points.csv are byte-identical from both paths: "
             f"{'OK' if same else 'FAILED'}.")
    runs = min(res["python"][0]) / min(res["cli"][0]) - 1
    whole = min(res["python"][1]) / min(res["cli"][1]) - 1
    sec.done(f"The Python path costs {100 * runs:+.1f} % on the model runs and {100 * whole:+.1f} % "
             f"on the whole command (best times; the interpreter's start and `import railuq` "
             f"included). Goal ≤ {100 * GOAL_PYTHON:.0f} %: "
             f"{goal(runs <= GOAL_PYTHON and whole <= GOAL_PYTHON)}.")
    return sec


# ------------------------------------------------------------------ 4./5. paper-wheel

def closed_form_q(k, c, t):
    """q(t) of m q'' + c q' + k q = 0, q(0) = q0, q'(0) = 0, any sign of the discriminant."""
    import numpy as np
    a = -c / (2.0 * M)
    wd = np.sqrt((k / M - a * a).astype(complex))
    small = np.abs(wd) < 1e-12
    wd_safe = np.where(small, 1.0, wd)
    q = Q0 * np.exp(a * t) * (np.cos(wd_safe * t) - a / wd_safe * np.sin(wd_safe * t))
    q = np.where(small, Q0 * np.exp(a * t) * (1.0 - a * t), q)  # critically damped limit
    return q.real


def reference(n):
    """Mean and Std of q at REF_TIMES on an n × n Gauss–Hermite grid."""
    import numpy as np
    from numpy.polynomial.hermite_e import hermegauss
    x, w = hermegauss(n)
    w = w / w.sum()
    kk, cc = np.meshgrid(K_MEAN + K_STD * x, C_MEAN + C_STD * x, indexing="ij")
    ww = np.outer(w, w)
    out = {}
    for t in REF_TIMES:
        q = closed_form_q(kk, cc, t)
        mean = float(np.sum(ww * q))
        std = float(np.sqrt(np.sum(ww * (q - mean) ** 2)))
        out[t] = (mean, std)
    return out


def at_times(cols):
    out = {}
    for t in REF_TIMES:
        i = int(abs(cols["time"] - t).argmin())
        if abs(cols["time"][i] - t) > 1e-9:
            die(f"time {t} is not on the output grid")
        out[t] = (float(cols["mean"][i]), float(cols["std"][i]))
    return out


def bench_paper_wheel(work):
    import numpy as np
    out_dir = work / "paper-wheel"
    cmd = [str(DRIVER), "run", "builtin:paper-wheel", "--out", str(out_dir), "--fresh"]
    t0 = time.perf_counter()
    watch = LoadWatch()
    print("\n== 4./5. running builtin:paper-wheel (SGM, SCM, LHS 1 000 / 10 000 / 50 000) ...",
          flush=True)
    wall, _, _ = run_cmd(cmd)
    other = watch.other_cores()
    ref = reference(40)
    ref60 = reference(60)
    ref_err = max(max(abs(ref[t][0] - ref60[t][0]), abs(ref[t][1] - ref60[t][1]))
                  for t in REF_TIMES)
    variants = []
    for name in ("sgm", "scm", "lhs-1000", "lhs-10000", "lhs-50000"):
        d = out_dir / name
        if not (d / "summary.json").is_file() or not (d / "q.csv").is_file():
            die(f"{d}: summary.json or q.csv missing after builtin:paper-wheel")
        s = json.loads((d / "summary.json").read_text())
        got = at_times(read_csv_cols(d / "q.csv"))
        dm = max(abs(got[t][0] - ref[t][0]) for t in REF_TIMES)
        ds = max(abs(got[t][1] - ref[t][1]) for t in REF_TIMES)
        variants.append((name, s, dm, ds))

    labels = {"sgm": "SGM, chaos order 6 (28 terms)", "scm": "SCM, 6 × 6 Gauss–Hermite nodes",
              "lhs-1000": "LHS 1 000", "lhs-10000": "LHS 10 000", "lhs-50000": "LHS 50 000"}
    sec4 = Section("4. Accuracy per model run (wheel, against an independent reference)",
                   ["method", "model runs", "wall time, runs (s)", "max |Δmean| (m)",
                    "max |ΔStd| (m)"])
    sec4.watch = watch
    for name, s, dm, ds in variants:
        runs = "1 Galerkin solve" if s["method"]["kind"] == "sgm" else f"{s['model_runs']:,}"
        sec4.row(labels[name], runs.replace(",", " "), fmt_s(s["wall_time_s"]),
                 f"{dm:.2e}", f"{ds:.2e}")
    sec4.cmd(f"target/release/uq-driver run builtin:paper-wheel --out {rel(out_dir)} --fresh")
    sec4.note(f"Reference: mean and Std of q at t = {', '.join(f'{t:g}' for t in REF_TIMES)} s "
              f"from the closed-form response q(t) = q0 e^(at) (cos ωd t − a/ωd sin ωd t), "
              f"a = −C/(2m), ωd = √(K/m − a²) (complex square root), m = 10, q0 = 0.1, "
              f"integrated over K ~ N(100, 10²), C ~ N(20, 2²) on a 40 × 40 Gauss–Hermite grid "
              f"(numpy `hermegauss`); it differs from a 60 × 60 grid by {ref_err:.1e}. "
              f"Δ = uq-driver's q.csv − reference, max over those 5 times. The LHS errors are "
              f"sampling errors (they shrink like 1/√n); SCM and SGM errors are those of the "
              f"quadrature/chaos truncation and of the RK4 time integration (h = 1e-3).")
    by = {n: (s, dm, ds) for n, s, dm, ds in variants}
    scm_err = max(by["scm"][1], by["scm"][2])
    lhs_err = max(by["lhs-50000"][1], by["lhs-50000"][2])
    sec4.other = other
    sec4.verdict = (f"SCM with 36 runs is {lhs_err / scm_err:.0f}× more accurate than LHS with "
                    f"50 000 runs (largest of the mean/Std errors: {scm_err:.1e} vs "
                    f"{lhs_err:.1e} m); no numeric goal is set here.")
    print(f"  -> {sec4.verdict}", flush=True)

    sec5 = Section("5. Wall time: SGM (N = 6) vs SCM 6 × 6 vs LHS 50 000 (same paper-wheel run)",
                   ["method", "model runs", "threads", "wall time, runs (s)",
                    "relative to SCM"])
    sec5.watch = watch
    scm_wall = by["scm"][0]["wall_time_s"]
    for name in ("sgm", "scm", "lhs-50000"):
        s = by[name][0]
        runs = "1 Galerkin solve" if s["method"]["kind"] == "sgm" else f"{s['model_runs']:,}"
        sec5.row(labels[name], runs.replace(",", " "), s["threads"], fmt_s(s["wall_time_s"]),
                 fmt_ratio(s["wall_time_s"] / scm_wall))
    sec5.note(f"`wall_time_s` of each variant's summary.json (the model runs or the Galerkin "
              f"solve, without analysis and report); the whole paper-wheel command took "
              f"{wall:.1f} s. Sampling and collocation use all cores (threads column).")
    sgm_wall = by["sgm"][0]["wall_time_s"]
    lhs_wall = by["lhs-50000"][0]["wall_time_s"]
    sec5.other = other
    sec5.verdict = (f"SGM {sgm_wall:.3f} s, SCM {scm_wall:.3f} s, LHS 50 000 {lhs_wall:.2f} s: "
                    f"LHS 50 000 takes {lhs_wall / scm_wall:.0f}× the time of SCM "
                    f"and {lhs_wall / sgm_wall:.0f}× that of SGM; no numeric goal is set here.")
    print(f"  -> {sec5.verdict}", flush=True)
    print(f"  (paper-wheel took {time.perf_counter() - t0:.1f} s; other processes kept "
          f"{other:.2f} cores busy meanwhile)", flush=True)
    return sec4, sec5


# ------------------------------------------------------------------ 6. real time

def bench_realtime(work, repeats, step_cost):
    sec = Section("6. Real-time factor of single simulations (`uq-driver simulate`, one thread)",
                  ["model, experiment", "simulated (s)", "wall, best (s)", "wall median (s)",
                   "CPU / wall", "real-time factor (best)", "(median)"])
    cases = [
        ("VehicleTrack, 0–2 s, step 1e-3 s, dt = 1e-4 s (default)", "VehicleTrack", 2.0,
         ["--stop", "2", "--step", "0.001"]),
        ("Bogie, full speed ramp 0–450 s, step 0.01 s, dt = 1e-3 s (default)", "Bogie", 450.0,
         []),
    ]
    rtf = {}
    for label, model, sim, extra in cases:
        out = work / f"{model}.csv"
        shown = (f"target/release/uq-driver simulate {rel(fmu(model))} "
                 f"{' '.join(extra)} --out {rel(out)}   # x{repeats}".replace("  ", " "))
        walls, util = simulate_timed(sec, model, extra, out, repeats, shown)
        with open(out) as f:
            n_rows = sum(1 for _ in f) - 1
        if model == "VehicleTrack" and n_rows != 2001:
            die(f"{out}: expected 2001 rows, got {n_rows}")
        b, m = best_median(walls)
        rtf[model] = (sim / b, sim / m)
        sec.row(label, f"{sim:g}", fmt_s(b), fmt_s(m), f"{statistics.median(util):.2f}",
                fmt_ratio(sim / b), fmt_ratio(sim / m))
    sec.note("Wall time of the whole command: open the FMU, load, instantiate, initialise, "
             "simulate, write the CSV of every output. The real-time factor is simulated time / "
             "wall time.")
    vt_ns = step_cost[("VehicleTrack", "fmi2DoStep")]["best_ns"]
    bo_ns = step_cost[("Bogie", "fmi2DoStep")]["best_ns"]
    sec.note(f"From section 1, the fmi2DoStep calls alone account for 2 000 × {vt_ns / 1e3:.1f} µs "
             f"= {2000 * vt_ns / 1e9:.3f} s of the VehicleTrack run (real-time factor "
             f"{2.0 / (2000 * vt_ns / 1e9):.1f}× for the stepping alone) and 45 000 × "
             f"{bo_ns / 1e3:.2f} µs = {45000 * bo_ns / 1e9:.3f} s of the Bogie run; the rest is "
             f"start-up and writing the CSV.")
    vt = rtf["VehicleTrack"][0]
    sec.done(f"VehicleTrack runs {vt:.1f}× faster than real time on one thread (best of "
             f"{repeats}). Goal ≥ {GOAL_RTF:g}×: {goal(vt >= GOAL_RTF)}. The Bogie's 450 s ramp "
             f"takes {450.0 / rtf['Bogie'][0]:.2f} s.")
    return sec


# ------------------------------------------------------------------ 6b. the full car

def bench_vehicle_realtime(work, repeats):
    """The Vehicle FMU (the full car, 66 states) on straight track at 40 m/s, one thread."""
    sec = Section("6b. Real-time factor of the full car (Vehicle, straight track, 40 m/s, "
                  "one thread)",
                  ["experiment", "simulated (s)", "wall, best (s)", "wall median (s)",
                   "CPU / wall", "real-time factor (best)", "(median)"])
    sim = 20.0
    out = work / "Vehicle.csv"
    extra = ["--set", "v=40", "--set", "ramp=0", "--stop", f"{sim:g}", "--step", "0.01"]
    shown = (f"target/release/uq-driver simulate {rel(fmu('Vehicle'))} {' '.join(extra)} "
             f"--out {rel(out)}   # x{repeats}")
    walls, util = simulate_timed(sec, "Vehicle", extra, out, repeats, shown)
    with open(out) as f:
        header = f.readline().strip().split(",")
        rows = [line.strip().split(",") for line in f if line.strip()]
    if len(rows) != round(sim / 0.01) + 1:
        die(f"{out}: expected {round(sim / 0.01) + 1} rows, got {len(rows)}")
    speed = [float(r[header.index("speed")]) for r in rows]
    if max(abs(v - 40.0) for v in speed) > 1e-9:
        die(f"{out}: the speed is not 40 m/s throughout")
    b, m = best_median(walls)
    sec.row(f"0–{sim:g} s, step 0.01 s, dt ≤ 1 ms (default), built-in S1002/UIC60 1:40 table, "
            f"the default initial disturbance", f"{sim:g}", fmt_s(b), fmt_s(m),
            f"{statistics.median(util):.2f}", fmt_ratio(sim / b), fmt_ratio(sim / m))
    sec.note("Wall time of the whole command (open the FMU, instantiate, compute the built-in "
             "contact table from the profiles, initialise, simulate, write the CSV of every "
             "output); real-time factor = simulated time / wall time.")
    sec.done(f"The full car runs {sim / b:.1f}× faster than real time at 40 m/s on one thread "
             f"(best of {repeats}). Goal ≥ {GOAL_VEHICLE_RTF:g}×: "
             f"{goal(sim / b >= GOAL_VEHICLE_RTF)}.")
    return sec


# ------------------------------------------------------------------ big model descriptions

GOAL_PARSE_1E5 = 1.0


def big_description(n):
    """A valid FMI 2.0 CS modelDescription.xml for the Wheel binary with n Real variables (every
    tenth a tunable parameter with start, unit and description, the others outputs), shaped like
    the flattened names of a Modelica export."""
    out = ['<?xml version="1.0" encoding="UTF-8"?>',
           '<fmiModelDescription fmiVersion="2.0" modelName="Big" guid="{big}" '
           'generationTool="bench/run.py">',
           '  <CoSimulation modelIdentifier="Wheel" canHandleVariableCommunicationStepSize="true"/>',
           '  <ModelVariables>']
    for i in range(n):
        if i % 10 == 0:
            out.append(f'    <ScalarVariable name="body[{i // 100}].spring[{i % 100}].k" '
                       f'valueReference="{i}" causality="parameter" variability="tunable" '
                       f'description="stiffness of spring {i}"><Real start="{1e6 + i}" unit="N/m"/>'
                       '</ScalarVariable>')
        else:
            out.append(f'    <ScalarVariable name="body[{i // 100}].x[{i % 100}]" '
                       f'valueReference="{i}" causality="output"><Real unit="m"/></ScalarVariable>')
    out.append('  </ModelVariables>')
    out.append('  <ModelStructure>')
    out.append('    <Outputs>')
    out += [f'      <Unknown index="{i + 1}"/>' for i in range(n) if i % 10 != 0]
    out.append('    </Outputs>')
    out.append('  </ModelStructure>')
    out.append('</fmiModelDescription>')
    return "\n".join(out) + "\n"


def bench_parse_description(work, repeats):
    sec = Section("Parsing big model descriptions (`uq-driver inspect`)",
                  ["variables", "modelDescription.xml (MB)", "wall, best (s)", "wall median (s)"])
    results = {}
    for n in (0, 10_000, 100_000):
        if n == 0:
            path, size = fmu("Wheel"), None
            with zipfile.ZipFile(path) as z:
                k = z.read("modelDescription.xml").count(b"<ScalarVariable")
            label = f"Wheel.fmu as built ({k} variables)"
        else:
            xml = big_description(n).encode()
            size = len(xml) / 1e6
            path = work / f"big-{n}.fmu"
            with zipfile.ZipFile(fmu("Wheel")) as src, \
                    zipfile.ZipFile(path, "w", zipfile.ZIP_DEFLATED) as dst:
                for item in src.infolist():
                    if item.filename != "modelDescription.xml":
                        dst.writestr(item, src.read(item.filename))
                dst.writestr("modelDescription.xml", xml)
            label = f"{n:,}".replace(",", " ")
        cmd = [str(DRIVER), "inspect", str(path)]
        sec.cmd(f"target/release/uq-driver inspect {rel(path)} > /dev/null   # x{repeats}")
        walls = []
        for _ in range(repeats):
            wall, _, stdout = run_cmd(cmd)
            walls.append(wall)
        if n and stdout.count("\n") < n:
            die(f"uq-driver inspect {rel(path)} listed {stdout.count(chr(10))} lines, expected > {n}")
        b, m = best_median(walls)
        results[n] = b
        sec.row(label, "–" if size is None else f"{size:.1f}", fmt_s(b), fmt_s(m))
    sec.note("Wall time of the whole command: extract the FMU, parse modelDescription.xml, load "
             "the binary (the Wheel's: the generated descriptions keep its modelIdentifier), print "
             "one line per variable. The descriptions are generated by bench/run.py "
             "(`big_description`); before format 2 the parser was quadratic (20 000 variables "
             "took 35 s to parse).")
    sec.done(f"100 000 variables: {fmt_s(results[100_000])} s at best for the whole inspect, "
             f"10 000: {fmt_s(results[10_000])} s (the Wheel as built: {fmt_s(results[0])} s). "
             f"Goal < {GOAL_PARSE_1E5:g} s for 100 000: "
             f"{goal(results[100_000] < GOAL_PARSE_1E5)}.")
    return sec


# ------------------------------------------------------------------ 7. VehicleTrack stepping

def bench_vt_stepping(work, other):
    """Section 7 from the JSON that benches/fmi_step.rs wrote in section 1 (same run); `other`
    is the load measured meanwhile."""
    sec = Section("7. VehicleTrack stepping: µs per substep, real-time factor, arithmetic bound",
                  ["resolution", "kernel", "best µs/substep", "median µs/substep",
                   "real-time factor (best)", "(median)", "flops/substep",
                   "loop Gflop/s", "bound µs", "of bound (best)"])
    data = json.loads((work / "vt_stepping.json").read_text())
    fast = {}
    for r in data["kernels"]:
        sec.row(r["resolution"], r["kernel"], f"{r['best_us']:.3f}", f"{r['median_us']:.3f}",
                fmt_ratio(r["rtf_best"]), fmt_ratio(r["rtf_median"]), f"{r['flops']:.0f}",
                f"{r['loop_gflops']:.1f}", f"{r['bound_us']:.3f}",
                f"{100 * r['bound_us'] / r['best_us']:.0f} %")
        key = (r["n"], r["nm"])
        if "[default here]" in r["kernel"]:
            fast[key] = r
        if r["kernel"] == "plain":
            fast[("plain", key)] = r
    sec.cmd("cargo bench --bench fmi_step -- --vt-json target/bench/vt_stepping.json   "
            "# (section 1's command)")
    sec.note("The stepping alone (`fmi2DoStep` → `VehicleTrack::do_step`, through the Rust API "
             "of the same library), in episodes of 20 substeps (default) or 50 (the 2e-5 s "
             "resolutions) of a run on the default irregularity, the kernels measured round robin "
             "(one episode each per round), so that other load on this shared machine "
             "disturbs them alike: compare ratios. `plain` is the reference implementation "
             "the fast kernel is tested against (the plain loop kept as the reference); the fast kernel "
             "runs on the widest instruction set the CPU has, chosen at run time (the shipped "
             "binary is built for baseline x86-64).")
    sec.note("Bound: the floating-point operations of one substep of the fast kernel, counted "
             "from its loops (benches/fmi_step/vt_kernels.rs, `flops_per_substep`), over the "
             "throughput measured here of a streaming multiply–add `y = a x + b y + c z` over "
             "L1-resident arrays (the shape of most of the substep's loops), on the same "
             "instruction set. It is a yardstick, not a hard limit: the FFT is denser than "
             "that loop, and at N = 511 the state no longer fits in L1.")
    acc = data["accuracy"]
    worst = max(a["max_rel_diff"] for a in acc)
    sec.note("Accuracy: largest |fast − plain| / max |plain| over Zc_acc, Zc_acc_front, "
             "Zc_acc_rear and P1..P4, sampled every 1 ms over 6 s: " +
             "; ".join(f"{a['case']}: {a['max_rel_diff']:.1e}" for a in acc) +
             f". Tolerance {GOAL_VT_ACCURACY:g}: {goal(worst <= GOAL_VT_ACCURACY)}. (The "
             "carbody acceleration is g − (Fs1 + Fs2)/Mc, a difference of two numbers near "
             "9.8 m/s²: on the dip run its largest value is a few mm/s², so rounding at "
             "1e-16 of g shows as a few 1e-13 of it.)")
    d, f, sp = fast.get((255, 255)), fast.get((511, 511)), fast.get((255, 511))
    if d is None or f is None or sp is None:
        die("vt_stepping.json lacks the default kernel at one of the resolutions")
    pd, pf, psp = fast[("plain", (255, 255))], fast[("plain", (511, 511))], \
        fast[("plain", (255, 511))]
    sec.note(f"Speed-up of the fast kernel over the plain one (best times, same rounds): "
             f"{pd['best_us'] / d['best_us']:.2f}× at N = NM = 255, "
             f"{pf['best_us'] / f['best_us']:.2f}× at N = NM = 511, "
             f"{psp['best_us'] / sp['best_us']:.2f}× at N = 255, NM = 511.")
    sec.note(f"The sleeper-passing variation of the wheel–rail force needs modes beyond the "
             f"sleeper grid, NM = 2N + 1 (N = 255, NM = 511: P1 varies by about 580 N peak to "
             f"peak on a perfect track at 300 km/h, against 13–14 N with NM = N at N = 255 or "
             f"511): that resolution steps at {fmt_ratio(sp['rtf_best'])} real time "
             f"({sp['best_us']:.2f} µs per 2e-5 s substep).")
    sec.note("Whole studies on VehicleTrack, model runs and analysis included, are timed in "
             "the section \"Analysis and report against the whole command\" of this same run "
             "(rows vehicle-track-scm-cov10: 81 runs of the default model; "
             "vehicle-track-sleeper-passing: 81 runs at N = 255, NM = 511, dt = 2e-5 s).")
    ok = (d["rtf_best"] >= GOAL_VT_DEFAULT and f["rtf_best"] >= GOAL_VT_FINE
          and worst <= GOAL_VT_ACCURACY)
    sec.other = other
    sec.done(f"Stepping alone: {fmt_ratio(d['rtf_best'])} real time at the default resolution "
             f"({d['best_us']:.2f} µs per 1e-4 s substep; median {fmt_ratio(d['rtf_median'])}), "
             f"goal ≥ {GOAL_VT_DEFAULT:g}×; {fmt_ratio(f['rtf_best'])} at N = NM = 511, "
             f"dt = 2e-5 s ({f['best_us']:.2f} µs per substep; median "
             f"{fmt_ratio(f['rtf_median'])}), goal ≥ {GOAL_VT_FINE:g}×; results within "
             f"{worst:.1e} of the plain kernel: {goal(ok)}.")
    return sec


# ------------------------------------------------------------------ analysis and report

def bench_analysis_report(work, repeats, checks, all_builtins):
    """Analysis + report against the whole command for the built-ins, and builtin:wheel-scm
    against OpenTURNS + fmpy and chaospy + fmpy (bench/analysis_report.py)."""
    sys.path.insert(0, str(Path(__file__).resolve().parent))
    import analysis_report
    return analysis_report.bench(sys.modules[__name__], work, DRIVER, repeats, checks,
                                 all_builtins)


# ------------------------------------------------------------------ high-dimensional goals

def bench_hd_goals(work):
    """The high-dimensional goals (Ishigami, borehole, g-function through the Functions test FMU; the
    VehicleTrack 8-D chaos), runs counted, beside OpenTURNS and chaospy (bench/hd_goals.py)."""
    sys.path.insert(0, str(Path(__file__).resolve().parent))
    import hd_goals
    return hd_goals.bench(sys.modules[__name__], work, DRIVER, FMU_DIR,
                          ROOT / "target" / "test-fmu")


def simulate_timed(sec, model, extra, out, repeats, shown):
    """`uq-driver simulate` of the built FMU `model` with the arguments `extra` into `out`,
    `repeats` times, shown in `sec` as `shown`; returns the wall times (s) and CPU / wall of
    each run."""
    cmd = [str(DRIVER), "simulate", str(fmu(model)), *extra, "--out", str(out)]
    sec.cmd(shown)
    walls, util = [], []
    for _ in range(repeats):
        wall, cpu, _ = run_cmd(cmd)
        walls.append(wall)
        util.append(cpu / wall)
    return walls, util


def bench_hd20(work, repeats):
    """The 20-input chaos's analysis time beside OpenTURNS' LARS on the same points
    (bench/hd20.py)."""
    sys.path.insert(0, str(Path(__file__).resolve().parent))
    import hd20
    return hd20.bench(sys.modules[__name__], work, DRIVER, ROOT / "target" / "test-fmu", repeats)


# ------------------------------------------------------------------ small probabilities

def bench_reliability_goals(work):
    """FORM, SORM, importance sampling and subset simulation on analytic limit states with
    known tails (the Functions test FMU), runs counted, beside OpenTURNS, and the coverage of
    their 95 % intervals over 20 seeds (bench/reliability_goals.py)."""
    sys.path.insert(0, str(Path(__file__).resolve().parent))
    import reliability_goals
    return reliability_goals.bench(sys.modules[__name__], work, DRIVER,
                                   ROOT / "target" / "test-fmu")


# ------------------------------------------------------------------ functional outputs

GOAL_FUNCTIONAL_S = 2.0        # analysis of the series on its principal components (s)
GOAL_FUNCTIONAL_RATIO = 15.0   # faster than the fit of every column
GOAL_FUNCTIONAL_DIFF = 0.005   # mean and Std within 0.5 % (of the series' largest Std)


def functional_study(functional):
    """builtin:vehicle-track-8d-pce with the series Zc_acc (3 001 columns) analysed
    `functional` ("columns" or "pca")."""
    text = (ROOT / "uq-driver/studies/vehicle-track-8d-pce.toml").read_text()
    text = text.replace('fmu = "VehicleTrack.fmu"', f'fmu = "{fmu("VehicleTrack")}"')
    text = text.replace("[[qoi]]", '[outputs]\nvariables = ["Zc_acc"]\n\n[[qoi]]', 1)
    return text + f'\n[analysis]\nfunctional = "{functional}"\n'


def bench_functional(work, repeats):
    """The same chaos study, its series fitted column by column and on its principal
    components: analysis time of each, and how far apart their statistics are."""
    sec = Section("Functional outputs: a chaos per time column against one per principal "
                  "component (VehicleTrack 8 inputs, order-3 LARS, 200 runs, 3 001 columns)",
                  ["functional", "chaoses fitted", "analysis, best (s)", "analysis, median (s)"])
    base = work / "functional"
    base.mkdir(parents=True, exist_ok=True)
    dirs = {f: base / f for f in ("columns", "pca")}
    for f, d in dirs.items():
        (base / f"vt-{f}.toml").write_text(functional_study(f))
    # The runs once (analysis settings do not change the records), then each analysis alone
    # on the resumed store.
    if dirs["columns"].exists():
        shutil.rmtree(dirs["columns"])
    run_cmd([str(DRIVER), "run", str(base / "vt-columns.toml"), "--out", str(dirs["columns"]),
             "--no-report"])
    if dirs["pca"].exists():
        shutil.rmtree(dirs["pca"])
    shutil.copytree(dirs["columns"] / "store", dirs["pca"] / "store")
    sec.cmd(f"target/release/uq-driver run {rel(base / 'vt-columns.toml')} --out "
            f"{rel(dirs['columns'])} --no-report   # the 200 runs, then the analysis x{repeats}")
    sec.cmd(f"cp -r {rel(dirs['columns'] / 'store')} {rel(dirs['pca'])}/ && target/release/"
            f"uq-driver run {rel(base / 'vt-pca.toml')} --out {rel(dirs['pca'])} --no-report"
            f"   # x{repeats}")
    times = {f: [] for f in dirs}
    for _ in range(repeats):
        for f, d in dirs.items():
            run_cmd([str(DRIVER), "run", str(base / f"vt-{f}.toml"), "--out", str(d),
                     "--no-report"])
            s = json.loads((d / "summary.json").read_text())
            if s["runs_this_invocation"]:
                die(f"{d}: the analysis reran {s['runs_this_invocation']} runs")
            times[f].append(s["timing"]["analysis_s"])
    fits = {}
    for f, d in dirs.items():
        s = json.loads((d / "summary.json").read_text())
        fits[f] = s["outputs"]["Zc_acc"]["functional"]
        b, m = best_median(times[f])
        sec.row(f, fits[f]["fits"], fmt_s(b), fmt_s(m))
    cols = {f: read_csv_cols(d / "Zc_acc.csv") for f, d in dirs.items()}
    sob = {f: read_csv_cols(d / "Zc_acc_sobol.csv") for f, d in dirs.items()}
    c, p = cols["columns"], cols["pca"]
    smax = max(c["std"])
    d_mean = max(abs(a - b) for a, b in zip(c["mean"], p["mean"])) / smax
    d_std = max(abs(a - b) for a, b in zip(c["std"], p["std"])) / smax
    resolved = [t for t, x in enumerate(c["std"]) if x > 1e-3 * smax]
    d_std_rel = max(abs(c["std"][t] - p["std"][t]) / c["std"][t] for t in resolved)
    def s1_diff(times):
        return max(abs(sob["columns"][k][t] - sob["pca"][k][t])
                   for k in sob["columns"] if k.startswith("S_") for t in times)
    vouched = [t for t, x in enumerate(c["std"]) if x > 0.1 * smax and c["loo"][t] < 0.05]
    d_s1 = s1_diff(vouched)
    d_s1_all = s1_diff([t for t, x in enumerate(c["std"]) if x > 1e-2 * smax])
    ratio = min(times["columns"]) / min(times["pca"])
    fp = fits["pca"]
    sec.note(f"{fp['modes']} principal components (retained_variance {fp['retained_variance']}; "
             f"they miss {fp['discarded_variance']:.1e} of the series' variance and at most "
             f"{fp['discarded_max']:.1e} of one column's). Largest difference over the 3 001 "
             f"times, pca against columns, as a share of the series' largest Std: mean "
             f"{100 * d_mean:.3f} %, Std {100 * d_std:.3f} %; the Std relative to its own value "
             f"(times where it is above 1e-3 of the largest) {100 * d_std_rel:.2f} %; "
             f"first-order Sobol' indices {d_s1:.4f} where the Std is above 10 % of the largest "
             f"and the column fit's leave-one-out error below 5 % ({len(vouched)} times), "
             f"{d_s1_all:.4f} where the Std is above 1 % of the largest. Both fits are "
             f"estimates: where the column fit's own leave-one-out error is a few per cent, "
             f"they differ by about as much.")
    ok = (min(times["pca"]) <= GOAL_FUNCTIONAL_S and ratio >= GOAL_FUNCTIONAL_RATIO
          and max(d_mean, d_std) <= GOAL_FUNCTIONAL_DIFF)
    sec.done(f"Analysis on the principal components {fmt_s(min(times['pca']))} s against "
             f"{fmt_s(min(times['columns']))} s column by column ({fmt_ratio(ratio)} faster), "
             f"mean and Std within {100 * max(d_mean, d_std):.2f} % of the largest Std "
             f"(goal ≤ {GOAL_FUNCTIONAL_S:g} s, ≥ {GOAL_FUNCTIONAL_RATIO:g}×, within "
             f"{100 * GOAL_FUNCTIONAL_DIFF:g} %): {goal(ok)}.")
    return sec


# ------------------------------------------------------------------ BENCHMARKS.md

# ------------------------------------------------------------------ --isolate overhead

ISOLATE_VT_STUDY = """name = "bench-isolate-vt"
description = "VehicleTrack, 40 Latin hypercube points of 6 s (the paper's section 5 settings)."
fmu = "VehicleTrack.fmu"
seed = 42
[experiment]
stop = 6.0
step = 0.002
[method]
kind = "lhs"
samples = 40
[[parameters]]
name = "Kpz"
mean = 1773000.0
cov = 0.1
[[parameters]]
name = "Csz"
mean = 120000.0
cov = 0.1
[fixed]
irregularity = 3
seed = 1
[outputs]
variables = ["Zc_acc", "P1"]
[[qoi]]
kind = "sperling"
name = "W"
signal = "Zc_acc"
direction = "vertical"
segment = 5.0
f_min = 0.5
f_max = 40.0
skip = 1.0
"""


def bench_isolate(work, repeats):
    """In-process runs against --isolate (a worker process per thread, one round trip of
    parameters and records per point) on VehicleTrack and on the Wheel."""
    sec = Section("9. uq-driver --isolate vs in-process (VehicleTrack 40 × 6 s, Wheel 1 000 × 5 s)",
                  ["study", "mode", "runs wall, best (s)", "runs median (s)",
                   "command wall, best (s)", "overhead (best runs)"])
    vt_toml = work / "bench-isolate-vt.toml"
    vt_toml.write_text(ISOLATE_VT_STUDY)
    studies = [("VehicleTrack", str(vt_toml), "Zc_acc.csv"),
               ("Wheel", "builtin:wheel-lhs-1000", "q.csv")]
    overheads, same = {}, True
    for name, study, csv_name in studies:
        res = {m: ([], []) for m in ("in-process", "isolate")}
        for m in res:
            flag = " --isolate" if m == "isolate" else ""
            sec.cmd(f"target/release/uq-driver run {rel(study) if study.endswith('.toml') else study} "
                    f"--out {rel(work / f'isolate-{name}-{m}')} --fresh{flag}   # x{repeats}")
        for _ in range(repeats):
            for m in res:  # alternate, so that slow phases of other load hit both
                out_dir = work / f"isolate-{name}-{m}"
                cmd = [str(DRIVER), "run", study, "--out", str(out_dir), "--fresh"]
                if m == "isolate":
                    cmd.append("--isolate")
                wall, _, _ = run_cmd(cmd)
                s = json.loads((out_dir / "summary.json").read_text())
                if s["failed_runs"]:
                    die(f"{out_dir}/summary.json: {s['failed_runs']} failed runs")
                res[m][0].append(s["wall_time_s"])
                res[m][1].append(wall)
        base = min(res["in-process"][0])
        for m in res:
            rb, rm = best_median(res[m][0])
            cb, _ = best_median(res[m][1])
            over = rb / base - 1.0
            sec.row(name, m, fmt_s(rb), fmt_s(rm), fmt_s(cb),
                    "—" if m == "in-process" else f"{100 * over:+.1f} %")
        overheads[name] = min(res["isolate"][0]) / base - 1.0
        ok = all((work / f"isolate-{name}-in-process" / f).read_bytes()
                 == (work / f"isolate-{name}-isolate" / f).read_bytes()
                 for f in (csv_name, "points.csv"))
        same = same and ok
        sec.note(f"Check: {csv_name} and points.csv of {name} are byte-identical in-process and "
                 f"with --isolate: {'OK' if ok else 'FAILED'}.")
    vt = overheads["VehicleTrack"]
    sec.done(f"--isolate costs {100 * vt:+.1f} % on the VehicleTrack runs (goal ≤ "
             f"{100 * GOAL_ISOLATE:.0f} %: {goal(vt <= GOAL_ISOLATE)}) and "
             f"{100 * overheads['Wheel']:+.1f} % on the Wheel (runs of well under a millisecond, "
             f"where the round trip per point would show; best times of runs alternated with "
             f"the in-process ones).")
    return sec, same



def write_markdown(path, mach, sections, total_wall, argv, checks_ok, lib_same):
    lines = [
        "# Benchmarks",
        "",
        "Speed of railuq's FMUs and of uq-driver, measured by `make bench` (`bench/run.py`, "
        "`benches/fmi_step.rs`). Every comparison below was measured side by side in the one "
        "run recorded here; the numbers are regenerated, never edited by hand. Tests never "
        "assert speed.",
        "",
        "Repeated measurements give the best (least disturbed) and the median time; ratios use "
        "the best times. Each section reports how many cores other processes kept busy while "
        "it ran: this machine may be shared with other builds, which makes the numbers noisy.",
        "",
        "## Command",
        "",
        "```sh",
        "make bench",
        "```",
        "",
        "It builds the release binaries, the FMUs and the venv (`make build fmu venv`), then "
        "runs `" + " ".join([".venv/bin/python", "bench/run.py"] + argv) + "`.",
        "",
        f"The whole run took {total_wall / 60:.1f} min.",
        "",
        "## Machine",
        "",
        "| | |",
        "|---|---|",
    ]
    for k, v in mach.items():
        lines.append(f"| {k} | {v} |")
    if lib_same is not None:
        lines.append(f"| FMU binary = target/release/librailuq.so | "
                     f"{'yes' if lib_same else 'NO (rebuilt after make fmu)'} |")
    lines.append("")
    if not checks_ok:
        lines += ["**A correctness check FAILED (see section 2/3): the comparisons are not "
                  "valid.**", ""]
    for s in sections:
        lines.append(s.markdown())
    Path(path).write_text("\n".join(lines).rstrip() + "\n")


SECTIONS = ("hd", "hd20", "vehicle", "reliability", "functional", "python")


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--repeats", type=int, default=3,
                    help="repetitions of the repeated measurements (default 3)")
    ap.add_argument("--md", default=None, help="output file (default BENCHMARKS.md; "
                    "target/bench/BENCHMARKS-quick.md with --quick)")
    ap.add_argument("--work", default=str(ROOT / "target" / "bench"),
                    help="scratch folder for study outputs (default target/bench)")
    ap.add_argument("--all-builtins", action="store_true",
                    help="also run the built-in studies that take an hour or more (the "
                         "bogie's 20 000-sample LHS) in the analysis/report section")
    ap.add_argument("--only", choices=SECTIONS, default=None,
                    help="run one section alone (default output "
                         "target/bench/BENCHMARKS-<section>.md)")
    ap.add_argument("--quick", action="store_true",
                    help="smoke test: 1 repeat, short fmi_step budget, simulate_fmu on 100 "
                         "points scaled to 1 000")
    args = ap.parse_args()
    if args.repeats < 1:
        ap.error("--repeats must be >= 1")
    repeats = 1 if args.quick else args.repeats
    md = Path(args.md) if args.md else (
        ROOT / "target" / "bench" / f"BENCHMARKS-{args.only}.md" if args.only
        else ROOT / "target" / "bench" / "BENCHMARKS-quick.md" if args.quick
        else ROOT / "BENCHMARKS.md")
    argv = sys.argv[1:]
    work = Path(args.work)
    t_start = time.perf_counter()
    try:
        check_prerequisites(args.only)
        work.mkdir(parents=True, exist_ok=True)
        env_fmu = os.environ.get("RAILUQ_FMU_DIR")
        os.environ["RAILUQ_FMU_DIR"] = str(FMU_DIR.resolve())  # the builtin studies' FMUs
        mach = machine()
        print("railuq benchmarks: " + ", ".join(f"{k}: {v}" for k, v in mach.items()), flush=True)
        checks = []
        if args.only:
            # One section alone: its sections (a list), and whether it uses the railuq FMUs.
            alone = {
                "hd": (lambda: bench_hd_goals(work), True),
                "hd20": (lambda: bench_hd20(work, repeats), False),
                "reliability": (lambda: bench_reliability_goals(work), False),
                "vehicle": (lambda: [bench_vehicle_realtime(work, repeats)], True),
                "python": (lambda: [bench_python(work, max(repeats, 5))], True),
                "functional": (lambda: [bench_functional(work, repeats)], True),
            }
            section, uses_fmus = alone[args.only]
            lib_same = (all(fmu_binary_sha(m) == sha256(LIB) for m in MODELS)
                        if uses_fmus else None)
            sections, same_threads, same_iso = section(), True, True
        else:
            sections, same_threads, same_iso, lib_same = all_sections(args, work, repeats,
                                                                      checks)
        if env_fmu is None:
            del os.environ["RAILUQ_FMU_DIR"]
    except BenchError as e:
        print(f"\nbench/run.py: error: {e}", file=sys.stderr)
        return 2
    checks_ok = all(ok for _, _, ok in checks) and same_threads and same_iso
    total = time.perf_counter() - t_start
    write_markdown(md, mach, sections, total, argv, checks_ok, lib_same)
    print(f"\nwrote {rel(md)} ({total:.0f} s in all)", flush=True)
    if not checks_ok:
        print("bench/run.py: a correctness check FAILED (see above)", file=sys.stderr)
        return 1
    return 0


def all_sections(args, work, repeats, checks):
    """Every section in order; returns (sections, same_threads, same_iso, lib_same)."""
    s1, step_cost, lib_same = bench_fmi_step(work, 0.3 if args.quick else 1.5)
    s2 = bench_wheel_1000(work, repeats, args.quick, checks)
    s3, same_threads = bench_threads(work, 1 if args.quick else max(repeats, 7))
    s3b = bench_python(work, 1 if args.quick else max(repeats, 5))
    s4, s5 = bench_paper_wheel(work)
    s6 = bench_realtime(work, repeats if args.quick else max(repeats, 5), step_cost)
    s6b = bench_vehicle_realtime(work, repeats if args.quick else max(repeats, 5))
    s_parse = bench_parse_description(work, repeats)
    s7 = bench_vt_stepping(work, s1.other)
    s_iso, same_iso = bench_isolate(work, repeats)
    s_analysis = bench_analysis_report(work, repeats, checks, args.all_builtins)
    s_functional = bench_functional(work, repeats)
    s_hd = bench_hd_goals(work) + bench_hd20(work, repeats)
    s_rel = bench_reliability_goals(work)
    return ([s1, s2, s3, s3b, s4, s5, s6, s6b, s7, s_parse, s_iso] + s_analysis
            + [s_functional] + s_hd + s_rel, same_threads, same_iso, lib_same)


if __name__ == "__main__":
    sys.exit(main())
