"""The Python package `railuq` (python/), as installed into the test venv by `make test`: every
public function against a real FMU, its numbers against the `uq-driver` command line's files
(bit for bit: the CSV numbers are the shortest text that reads back to the same double), its
errors against the command line's messages, Ctrl-C and resume, and the glibc floor of the
binaries it ships. The package must be installed (`make test` does it): a missing package is a
failure, not a skip."""
import csv
import io
import json
import os
import signal
import subprocess
import sys
import zipfile

import numpy as np
import pytest

from binaries import max_glibc
from conftest import DRIVER, FMU_DIR, ROOT
# The C test FMUs, built by test_test_fmus.py's fixtures, and its reference for them.
from test_test_fmus import built, features_fmu, functions_fmu, hashed_normal  # noqa: F401

try:
    import railuq
except ImportError as e:  # pragma: no cover - the message is the point
    pytest.fail(f"the railuq package is not installed in {sys.executable} ({e}): "
                "`make test` installs it (python3 -m pip install ./python)",
                pytrace=False)

MODELS = ["Bogie", "Vehicle", "VehicleTrack", "Wheel"]
# The newest glibc a shipped binary may need (the README's table); zig links against 2.17.
GLIBC_FLOOR = (2, 28)

# A sampled study, as a dict of the TOML schema: the wheel by Latin hypercube, a scalar
# quantity with an exceedance limit.
SAMPLED = {
    "name": "wheel-lhs-py",
    "fmu": "Wheel.fmu",
    "seed": 7,
    "experiment": {"start": 0.0, "stop": 2.0, "step": 0.01},
    "parameters": [
        {"name": "K", "distribution": "normal", "mean": 100.0, "std": 10.0},
        {"name": "C", "distribution": "normal", "mean": 20.0, "std": 2.0},
    ],
    "outputs": {"variables": ["q"]},
    "qoi": [{"kind": "max_abs", "name": "q_peak", "signal": "q", "from": 0.5,
             "limits": [0.04]}],
    "method": {"kind": "lhs", "samples": 300},
}


def in_ci():
    return os.environ.get("CI", "").strip().lower() not in ("", "0", "false", "no")


def driver(*args, check=True):
    if not DRIVER.is_file():
        pytest.fail(f"{DRIVER} is missing: run `make build` first")
    env = dict(os.environ, RAILUQ_FMU_DIR=str(FMU_DIR))
    p = subprocess.run([str(DRIVER), *map(str, args)], capture_output=True, text=True, env=env)
    if check and p.returncode != 0:
        pytest.fail(f"uq-driver {' '.join(map(str, args))} failed:\n{p.stderr}")
    return p


def cli_error(stderr):
    """The error the command line printed, as the package words it: the text after
    `uq-driver: error: ` (with its continuation lines), and each `uq-driver: hint: ...` line
    as `hint: ...`."""
    lines = stderr.splitlines()
    first = next(k for k, line in enumerate(lines) if line.startswith("uq-driver: error: "))
    out = [lines[first][len("uq-driver: error: "):]]
    for line in lines[first + 1:]:
        out.append(line[len("uq-driver: "):] if line.startswith("uq-driver: hint: ") else line)
    return "\n".join(out)


def read_csv(path_or_text):
    text = path_or_text if "\n" in str(path_or_text) else open(path_or_text).read()
    rows = list(csv.reader(io.StringIO(text)))
    return rows[0], rows[1:]


def column(path, name):
    header, rows = read_csv(path)
    i = header.index(name)
    return np.array([float(r[i]) for r in rows])


def cli_study(tmp_path, study):
    """Runs `study` (a railuq.Study) with the command line, from its TOML text in a file."""
    toml = tmp_path / f"{study.name}.toml"
    toml.write_text(study.toml)
    out = tmp_path / "cli"
    driver("run", toml, "--out", out, "--no-report")
    return out


def assert_same_statistics(results, out):
    """The package's statistics equal the command line's CSV files and summary.json bits."""
    for var in results.outputs:
        csvf = out / f"{var}.csv"
        assert np.array_equal(results.time, column(csvf, "time"))
        assert np.array_equal(results.mean(var), column(csvf, "mean"))
        assert np.array_equal(results.std(var), column(csvf, "std"))
        for level, values in results.quantiles(var).items():
            assert np.array_equal(values, column(csvf, f"q{100 * level:g}")), level
    summary = json.loads((out / "summary.json").read_text())
    assert summary["quantities"] == {name: results.quantity(name) for name in results.quantities}
    for key in ("quantities", "outputs", "parameters", "method", "model_runs", "failed_runs"):
        assert results.summary[key] == summary[key], key


# ---------------------------------------------------------------- FMUs and simulate

def test_the_package_ships_the_four_fmus_and_fmu_path_finds_them():
    assert railuq.fmus() == MODELS
    for name in MODELS:
        path = railuq.fmu_path(name)
        assert path == railuq.fmu_path(name + ".fmu")
        with zipfile.ZipFile(path) as z:
            assert "modelDescription.xml" in z.namelist()
            assert f"binaries/linux64/{name}.so" in z.namelist()
    with pytest.raises(railuq.FmuError, match="no FMU 'Wagon' in the package.*VehicleTrack"):
        railuq.fmu_path("Wagon")


def test_simulate_equals_uq_driver_simulate_bit_for_bit(tmp_path):
    fmu = railuq.fmu_path("Wheel")
    df = railuq.simulate(fmu, set={"K": 90.0, "C": 21.5}, stop=1.5, step=0.01)
    out = tmp_path / "wheel.csv"
    driver("simulate", fmu, "--set", "K=90", "--set", "C=21.5", "--stop", "1.5", "--step", "0.01",
           "--out", out)
    header, rows = read_csv(out)
    assert list(df.columns) == header
    for i, name in enumerate(header):
        assert df[name].dtype == np.float64
        assert np.array_equal(df[name].to_numpy(), [float(r[i]) for r in rows]), name
    assert len(df) == 151


def test_simulate_returns_the_calculated_strings_fmpy_reads():
    """VehicleTrack's solver.kernel (the instruction sets its equations ran on), read by fmpy
    from the same FMU after one step, is in the DataFrame's attrs."""
    from fmpy import extract, read_model_description
    from fmpy.fmi2 import FMU2Slave

    fmu = railuq.fmu_path("VehicleTrack")
    df = railuq.simulate(fmu, stop=0.002, step=0.001, outputs=["Zc"])
    md = read_model_description(fmu)
    vr = next(v.valueReference for v in md.modelVariables if v.name == "solver.kernel")
    slave = FMU2Slave(guid=md.guid, unzipDirectory=extract(fmu),
                      modelIdentifier=md.coSimulation.modelIdentifier, instanceName="k")
    slave.instantiate()
    try:
        slave.setupExperiment(startTime=0.0)
        slave.enterInitializationMode()
        slave.exitInitializationMode()
        slave.doStep(currentCommunicationPoint=0.0, communicationStepSize=0.001)
        kernel = slave.getString([vr])[0].decode()
    finally:
        slave.terminate()
        slave.freeInstance()
    assert kernel, "the FMU gave an empty solver.kernel"
    assert df.attrs["calculated_strings"] == {"solver.kernel": kernel}
    # The Wheel has none.
    assert railuq.simulate(railuq.fmu_path("Wheel"), stop=0.1, step=0.1).attrs[
        "calculated_strings"] == {}


def test_simulate_without_pandas_returns_a_dict_of_float64_arrays(monkeypatch):
    monkeypatch.setitem(sys.modules, "pandas", None)  # `import pandas` raises ImportError
    cols = railuq.simulate(railuq.fmu_path("Wheel"), outputs=["q"], stop=0.5, step=0.1)
    assert list(cols) == ["time", "q"]
    for a in cols.values():
        assert isinstance(a, np.ndarray) and a.dtype == np.float64 and a.shape == (6,)
    assert np.allclose(cols["time"], np.linspace(0, 0.5, 6), rtol=0, atol=1e-12)
    # The calculated strings were dropped without pandas: they are the dict's attrs.
    assert isinstance(cols, dict) and cols.attrs == {"calculated_strings": {}}
    vt = railuq.simulate(railuq.fmu_path("VehicleTrack"), stop=0.002, step=0.001,
                         outputs=["Zc"])
    assert set(vt.attrs["calculated_strings"]) == {"solver.kernel"}
    assert vt.attrs["calculated_strings"]["solver.kernel"]


def test_simulate_errors_carry_the_command_lines_message(tmp_path):
    fmu = railuq.fmu_path("Wheel")
    with pytest.raises(railuq.Error) as e:
        railuq.simulate(fmu, set={"Kx": 1.0}, stop=0.1, step=0.01)
    p = driver("simulate", fmu, "--set", "Kx=1", "--stop", "0.1", "--step", "0.01",
               "--out", tmp_path / "x.csv", check=False)
    assert p.returncode != 0
    assert "Kx" in str(e.value) and "hint: 'Kx': did you mean 'K'?" in str(e.value)
    assert str(e.value) == cli_error(p.stderr)


def test_simulate_a_c_test_fmu_gives_its_closed_form(functions_fmu):
    """A Reference-FMU-like FMU written in C (uq-driver/tests/fmus): y = x1 + function + sigma_h
    * N(seed), y_t = y (1 + t), the reference computed in test_test_fmus.py."""
    df = railuq.simulate(functions_fmu, set={"function": 4, "seed": 9, "x1": 0.5, "x2": -2.0,
                                             "sigma_h": 2.0}, stop=2.0, step=0.25)
    y = 0.5 + 4.0 + 2.0 * hashed_normal(9)
    np.testing.assert_allclose(df["y"], y, rtol=1e-14)
    np.testing.assert_allclose(df["y_t"], y * (1 + df["time"]), rtol=1e-14)
    assert len(df) == 9


def test_simulate_sets_parameters_of_every_type(features_fmu):
    text = "grüße, 世界"
    df = railuq.simulate(features_fmu, set={"int_param": -17, "bool_param": True,
                                            "enum_param": 3, "string_param": text}, step=0.5,
                         outputs=["int_out", "bool_out", "enum_out", "string_len"])
    assert list(df.columns) == ["time", "int_out", "bool_out", "enum_out", "string_len"]
    assert (df.dtypes == np.float64).all()
    assert list(df["int_out"]) == [-17.0] * 3 and list(df["bool_out"]) == [1.0] * 3
    assert list(df["enum_out"]) == [3.0] * 3
    assert list(df["string_len"]) == [float(len(text.encode()))] * 3


# ---------------------------------------------------------------- studies

def test_wheel_scm_equals_the_command_line_bit_for_bit(tmp_path):
    study = railuq.builtin("wheel-scm")
    assert (study.name, study.parameters, study.outputs) == ("wheel-scm", ["K", "C"], ["q"])
    with study.run(out=tmp_path / "py", progress=False, report=False) as r:
        out = tmp_path / "cli"
        driver("run", "builtin:wheel-scm", "--out", out, "--no-report")
        assert_same_statistics(r, out)
        assert r.time.dtype == np.float64 and r.time.shape == (501,)
        assert r.mean("q").shape == r.std("q").shape == (501,)
        s = r.sobol("q")
        assert set(s) >= {"first", "total"} and list(s["first"]) == ["K", "C"]
        assert s["first"]["K"].shape == (501,)
        df = r.to_pandas()
        assert df.shape[0] == 501 and np.array_equal(df[("q", "mean")].to_numpy(), r.mean("q"))


def test_a_sampled_study_from_a_dict_equals_the_command_line_bit_for_bit(tmp_path):
    study = railuq.Study.from_dict(SAMPLED)
    assert study.origin == "dict" and study.quantities == ["q_peak"]
    r = study.run(out=tmp_path / "py", threads=2, progress=False, report=False)
    out = cli_study(tmp_path, study)
    assert_same_statistics(r, out)
    assert isinstance(r.mean("q_peak"), float)
    (row,) = r.exceedance["q_peak"]
    cli_q = json.loads((out / "summary.json").read_text())["quantities"]["q_peak"]
    assert row["limit"] == 0.04 and 0.0 < row["p"] < 1.0
    assert [row["limit"], row["p"], row["std_error"]] == cli_q["exceedance"][0]
    # The same study from TOML text and from a file gives the same numbers.
    again = railuq.Study.from_toml(study.toml).run(progress=False)
    assert np.array_equal(again.mean("q"), r.mean("q"))
    again.close()
    assert not again.out.exists(), "a temporary output folder outlives close()"
    from_file = railuq.Study.from_file(tmp_path / f"{study.name}.toml")
    assert from_file.toml == study.toml


def test_a_misspelt_key_of_a_study_dict_raises_study_error_naming_it():
    bad = dict(SAMPLED, methd=SAMPLED["method"])
    del bad["method"]
    with pytest.raises(railuq.StudyError) as e:
        railuq.Study.from_dict(bad)
    assert "methd" in str(e.value) and "method" in str(e.value).split("methd", 1)[1]
    bad = dict(SAMPLED, parameters=[dict(SAMPLED["parameters"][0], distribution="normall")])
    with pytest.raises(railuq.StudyError, match="normall"):
        railuq.Study.from_dict(bad)
    with pytest.raises(TypeError, match="experiment.stop"):
        railuq.Study.from_dict(dict(SAMPLED, experiment={"stop": object()}))
    with pytest.raises(railuq.StudyError, match="did you mean 'wheel-scm'"):
        railuq.builtin("wheel-scn")


def test_study_file_errors_are_the_command_lines_messages(tmp_path):
    f = tmp_path / "bad.toml"
    f.write_text(railuq.builtin("wheel-scm").toml.replace("nodes = 6", "nodez = 6"))
    with pytest.raises(railuq.StudyError) as e:
        railuq.Study.from_file(f)
    p = driver("run", f, "--out", tmp_path / "out", check=False)
    assert p.returncode != 0
    assert str(e.value) == cli_error(p.stderr)


# ---------------------------------------------------------------- surrogate

def test_surrogate_equals_uq_driver_surrogate_eval_and_sample(tmp_path):
    r = railuq.builtin("wheel-scm").run(out=tmp_path / "scm", progress=False, report=False)
    s = r.surrogate("q")
    assert s.inputs == ["K", "C"] and np.array_equal(s.times, r.time)
    p = driver("surrogate", "eval", r.out, "--at", "K=95", "--at", "C=21")
    header, rows = read_csv(p.stdout)
    cli = np.array([float(row[2]) for row in rows if row[0] == "q"])
    y = s({"K": 95.0, "C": 21.0})
    assert y.dtype == np.float64 and y.shape == (501,)
    assert np.array_equal(y, cli)
    # Vectorised: n points at once, row i the value at point i.
    pts = np.array([[95.0, 21.0], [100.0, 20.0], [110.0, 18.5]])
    ys = s(pts)
    assert ys.shape == (3, 501) and np.array_equal(ys[0], cli)
    assert np.array_equal(ys[2], s(pts[2]))
    assert np.array_equal(s({"K": pts[:, 0], "C": pts[:, 1]}), ys)
    # sample(n): the points and values of `uq-driver surrogate sample`.
    x, v = s.sample(5, seed=3)
    assert x.shape == (5, 2) and v.shape == (5, 501) and x.dtype == v.dtype == np.float64
    p = driver("surrogate", "sample", r.out, "-n", 5, "--seed", 3, "--time", r.time[-1])
    header, rows = read_csv(p.stdout)
    got = np.array([[float(row[header.index(c)]) for c in ("K", "C")] for row in rows])
    assert np.array_equal(x, got)
    last = [c for c in header if c.startswith("q@")]
    assert np.array_equal(v[:, -1], [float(row[header.index(last[0])]) for row in rows])
    with pytest.raises(railuq.SurrogateError, match="Kx"):
        s({"Kx": 1.0})
    with pytest.raises(KeyError):
        r.surrogate("nope")


# ---------------------------------------------------------------- Ctrl-C and resume

def test_ctrl_c_stops_a_study_cleanly_and_a_second_run_resumes(tmp_path, monkeypatch):
    study = railuq.Study.from_dict(dict(SAMPLED, name="wheel-lhs-stop",
                                        method={"kind": "lhs", "samples": 5000}))
    import threading

    from railuq import _progress

    seen = []
    update = _progress.Display.update

    def interrupting(self, done, total, messages):
        seen.append((done, total))
        update(self, done, total, messages)
        if 0 < done < total and len(seen) < 1000 and not getattr(self, "sent", False):
            self.sent = True
            # A real Ctrl-C, sent to the main thread, whose handler raises KeyboardInterrupt.
            signal.pthread_kill(threading.main_thread().ident, signal.SIGINT)

    # Python's own SIGINT handler, as in a terminal or Jupyter: a process started in the
    # background by a shell without job control (`make test &`) inherits SIGINT ignored, and
    # Python then installs no handler at all.
    previous = signal.signal(signal.SIGINT, signal.default_int_handler)
    monkeypatch.setattr(_progress.Display, "update", interrupting)
    out = tmp_path / "py"
    with pytest.raises(KeyboardInterrupt):
        study.run(out=out, threads=1, report=False)
    first_total = seen[-1][1]
    assert first_total == 5000
    seen.clear()
    monkeypatch.setattr(_progress.Display, "update", update)

    def recording(self, done, total, messages):
        seen.append((done, total))
        update(self, done, total, messages)

    monkeypatch.setattr(_progress.Display, "update", recording)
    r = study.run(out=out, report=False)
    resumed_total = max(t for _, t in seen)
    assert 0 < resumed_total < 5000, "the second run did not resume the first one's points"
    assert r.summary["runs_resumed"] == 5000 - resumed_total
    assert_same_statistics(r, cli_study(tmp_path, study))
    signal.signal(signal.SIGINT, previous)


def test_a_running_study_releases_the_gil(tmp_path):
    """Another Python thread keeps running while the study's points run."""
    import threading

    study = railuq.Study.from_dict(dict(SAMPLED, name="wheel-lhs-gil",
                                        method={"kind": "lhs", "samples": 3000}))
    count, stop = [0], threading.Event()

    def spin():
        while not stop.is_set():
            count[0] += 1

    t = threading.Thread(target=spin)
    t.start()
    try:
        before = count[0]
        r = study.run(out=tmp_path / "py", threads=1, progress=False, report=False)
        during = count[0] - before
    finally:
        stop.set()
        t.join()
    assert r.summary["model_runs"] == 3000
    assert during > 10_000, f"the other thread ran {during} loops while the study ran"


# ---------------------------------------------------------------- the command line

def test_python_m_railuq_is_the_command_line():
    p = subprocess.run([sys.executable, "-m", "railuq", "list"], capture_output=True, text=True)
    assert p.returncode == 0, p.stderr
    assert p.stdout == driver("list").stdout
    p = subprocess.run([sys.executable, "-m", "railuq", "run", "wheel-scn", "--out", "unused"],
                       capture_output=True, text=True)
    assert p.returncode != 0
    assert cli_error(p.stderr) == cli_error(driver("run", "wheel-scn", "--out", "unused",
                                                   check=False).stderr)
    assert "did you mean" in p.stderr


def test_python_m_railuq_run_isolate_starts_workers_and_equals_the_command_line(tmp_path):
    """`--isolate` from the package: its workers are the `railuq` command installed beside the
    interpreter (the interpreter itself has no `worker` subcommand), and the numbers are the
    command line's, bit for bit."""
    scripts = __import__("sysconfig").get_path("scripts")
    command = os.path.join(scripts, "railuq")
    assert os.access(command, os.X_OK), f"the package installed no `railuq` command in {scripts}"
    env = {k: v for k, v in os.environ.items() if k != "UQ_DRIVER_EXE"}
    py = tmp_path / "py"
    p = subprocess.run([sys.executable, "-m", "railuq", "run", "builtin:wheel-scm", "--isolate",
                        "--out", str(py), "--no-report"], capture_output=True, text=True, env=env)
    assert p.returncode == 0, p.stderr
    cli = tmp_path / "cli"
    driver("run", "builtin:wheel-scm", "--out", cli, "--no-report")
    assert (py / "q.csv").read_bytes() == (cli / "q.csv").read_bytes()
    # The `railuq` command is the same command line.
    p = subprocess.run([command, "list"], capture_output=True, text=True, env=env)
    assert p.returncode == 0, p.stderr
    assert p.stdout == driver("list").stdout


def test_the_command_line_and_a_study_run_start_without_importing_numpy(tmp_path):
    """numpy's import (about 0.1 s) is paid only when an array is asked for: not by the command
    line (nor so by each --isolate worker), nor by a study's runs."""
    code = ("import sys, railuq, railuq.__main__; "
            "r = railuq.builtin('wheel-scm').run(progress=False, report=False); "
            "assert 'numpy' not in sys.modules, 'imported by the run'; "
            "r.mean('q'); assert 'numpy' in sys.modules; r.close()")
    p = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, cwd=tmp_path)
    assert p.returncode == 0, p.stderr


def test_to_xarray_holds_the_statistics_of_to_pandas(tmp_path):
    xr = pytest.importorskip("xarray") if not in_ci() else __import__("xarray")
    with railuq.Study.from_dict(SAMPLED).run(out=tmp_path / "x", progress=False,
                                             report=False) as r:
        ds = r.to_xarray()
        assert isinstance(ds, xr.Dataset) and ds.attrs["study"] == "wheel-lhs-py"
        assert np.array_equal(ds["time"].to_numpy(), r.time)
        assert np.array_equal(ds["q_mean"].to_numpy(), r.mean("q"))
        assert np.array_equal(ds["q_std"].to_numpy(), r.std("q"))
        assert ds["q_mean"].dims == ("time",)
        df = r.to_pandas()
        for name, stat in df.columns:
            assert np.array_equal(ds[f"{name}_{stat}"].to_numpy(), df[(name, stat)].to_numpy())
        assert float(ds["q_peak_mean"]) == r.mean("q_peak")
        assert float(ds["q_peak_std"]) == r.std("q_peak")


# ---------------------------------------------------------------- the binaries

def zig_available():
    p = subprocess.run([sys.executable, "-m", "ziglang", "version"], capture_output=True)
    return p.returncode == 0


def shipped_binaries():
    """(what, ELF bytes) of the extension module, the package's FMUs' and target/fmu's linux64
    libraries, and uq-driver."""
    out = [("railuq._railuq", open(railuq._railuq.__file__, "rb").read())]
    for where, folder in (("package", railuq.FMU_DIR), ("target/fmu", FMU_DIR)):
        for name in MODELS:
            with zipfile.ZipFile(folder / f"{name}.fmu") as z:
                out.append((f"{where} {name}.fmu", z.read(f"binaries/linux64/{name}.so")))
    out.append(("uq-driver", DRIVER.read_bytes()))
    return out


def test_binaries_need_at_most_glibc_2_28():
    too_new = [f"{what} needs GLIBC_{'.'.join(map(str, max_glibc(data)))}"
               for what, data in shipped_binaries() if max_glibc(data) > GLIBC_FLOOR]
    if too_new and not zig_available():
        message = ("zig is not installed (`pip install ziglang` into the venv; `make test` does), "
                   "so the binaries were linked against the build machine's glibc: "
                   + "; ".join(too_new))
        if in_ci():
            pytest.fail(message + " (CI is set: this is a failure, not a skip)")
        pytest.skip(message)
    assert not too_new, too_new


def test_the_wheel_is_tagged_manylinux2014_when_zig_links_it():
    """A wheel linked against glibc 2.17 says so in its name (pip on an old system installs
    only wheels whose tag it accepts)."""
    wheels = sorted((ROOT / "target" / "wheels").glob("railuq-*.whl"))
    if not wheels:
        pytest.fail("no wheel in target/wheels: `make wheel` builds it (make test does)")
    if not zig_available():
        message = "zig is not installed: the wheel is linked against the build machine's glibc"
        if in_ci():
            pytest.fail(message + " (CI is set: this is a failure, not a skip)")
        pytest.skip(message)
    (wheel,) = wheels
    assert "manylinux_2_17_x86_64" in wheel.name or "manylinux2014_x86_64" in wheel.name, wheel


def test_shipped_fmu_libraries_export_exactly_the_fmi_functions(tmp_path):
    from test_win64_wine import FMI2_CS_FUNCTIONS

    for name in MODELS:
        with zipfile.ZipFile(railuq.fmu_path(name)) as z:
            so = tmp_path / f"{name}.so"
            so.write_bytes(z.read(f"binaries/linux64/{name}.so"))
        p = subprocess.run(["objdump", "-T", str(so)], capture_output=True, text=True,
                           check=True)
        defined = sorted(line.split()[-1] for line in p.stdout.splitlines()
                         if " DF " in line and "*UND*" not in line)
        assert defined == FMI2_CS_FUNCTIONS, name


# ---------------------------------------------------------------- the example notebook

def test_example_notebook_runs(tmp_path, monkeypatch):
    """examples/railuq.ipynb: its code cells run in order, in one namespace (as a kernel runs
    them), from a scratch folder."""
    nb = json.loads((ROOT / "examples" / "railuq.ipynb").read_text())
    monkeypatch.chdir(tmp_path)
    namespace = {"__name__": "__main__"}
    cells = [c for c in nb["cells"] if c["cell_type"] == "code"]
    assert cells
    for i, cell in enumerate(cells):
        code = compile("".join(cell["source"]), f"railuq.ipynb cell {i}", "exec")
        exec(code, namespace)
    assert (tmp_path / "out" / "wheel-scm" / "summary.json").is_file()
