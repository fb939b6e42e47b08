"""Importer: `uq-driver simulate` against fmpy on the same FMUs, with parameters of
every type, input signals, an FMU that ends the simulation, a stop time off the grid, and
VehicleTrack's measured track profile. Where fmpy and uq-driver take the same steps the
trajectories must be equal bit for bit (the CSV numbers read back exactly)."""
import math
import subprocess

import numpy as np
import pytest
from fmpy import simulate_fmu

from conftest import DRIVER, build_test_fmus, fmu_path


@pytest.fixture(scope="module")
def features():
    return str(build_test_fmus()["Features"][0])


def driver(fmu, tmp_path, *args):
    """Runs `uq-driver simulate FMU ARGS --out CSV`; returns the CSV as a structured array and
    the stderr."""
    if not DRIVER.is_file():
        pytest.fail(f"{DRIVER} is missing: run `make build` first")
    out = tmp_path / "ours.csv"
    p = subprocess.run([str(DRIVER), "simulate", fmu, *args, "--out", str(out)],
                       capture_output=True, text=True)
    assert p.returncode == 0, p.stderr
    return np.genfromtxt(out, delimiter=",", names=True), p.stderr


def assert_same(ours, ref, names):
    assert len(ours) == len(ref), (len(ours), len(ref))
    assert np.array_equal(ours["time"], np.asarray(ref["time"], float))
    for n in names:
        assert np.array_equal(ours[n], np.asarray(ref[n], float)), n


def test_parameters_of_every_type_give_fmpys_trajectories(features, tmp_path):
    start = {"int_param": -17, "bool_param": True, "enum_param": 3, "string_param": "grüße, 世界",
             "u": 0.25, "gain": -3.5}
    names = ["u_echo", "u_integral", "u_gain", "int_out", "enum_out", "string_len", "bool_out",
             "file_value"]
    args = []
    for k, v in start.items():
        v = str(v).lower() if isinstance(v, bool) else v
        args += ["--set", f"{k}={v}"]
    ours, _ = driver(features, tmp_path, *args, "--stop", "1", "--step", "0.1")
    ref = simulate_fmu(features, start_values=start, stop_time=1.0, output_interval=0.1,
                       output=names)
    assert_same(ours, ref, names)
    assert list(ours["int_out"]) == [-17] * 11 and list(ours["string_len"]) == [15] * 11


def test_input_signals_give_fmpys_trajectories(features, tmp_path):
    signal = np.array([(0.0, 0.0, 0, False), (0.35, 1.0, 2, False), (0.5, 1.0, 2, False),
                       (0.5, 3.0, 5, True), (0.8, -2.0, 5, True), (1.0, 0.5, -1, False)],
                      dtype=[("time", float), ("u", float), ("k", np.int32), ("flag", bool)])
    csv = tmp_path / "signal.csv"
    with open(csv, "w") as f:
        f.write("time,u,k,flag\n")
        for t, u, k, flag in signal:
            f.write(f"{float(t)!r},{float(u)!r},{int(k)},{str(bool(flag)).lower()}\n")
    names = ["u_echo", "u_integral", "k_echo", "flag_echo"]
    ours, _ = driver(features, tmp_path, "--input", str(csv), "--stop", "1", "--step", "0.05",
                     *sum((["--output", n] for n in names), []))
    # Every jump of the signal (0.5 for u, 0.35/0.5/1.0 for k and flag) is on the 0.05 grid, so
    # fmpy adds no communication point of its own and both take the same steps.
    ref = simulate_fmu(features, input=signal, stop_time=1.0, output_interval=0.05,
                       output=names)
    assert_same(ours, ref, names)


@pytest.mark.parametrize("stop_at", [0.55, 0.5, 0.3000000000000001])
def test_an_fmu_that_ends_the_simulation_ends_as_in_fmpy(features, tmp_path, stop_at):
    names = ["u_integral", "u_echo"]
    ours, err = driver(features, tmp_path, "--set", f"stop_at={stop_at!r}", "--set", "u=2",
                       "--stop", "2", "--step", "0.1", "--output", "u_integral",
                       "--output", "u_echo")
    ref = simulate_fmu(features, start_values={"stop_at": stop_at, "u": 2.0}, stop_time=2.0,
                       output_interval=0.1, output=names)
    assert_same(ours, ref, names)
    assert "ended the simulation" in err


def test_a_stop_time_off_the_grid_ends_with_fmpys_shorter_step(features, tmp_path):
    names = ["u_integral"]
    ours, _ = driver(features, tmp_path, "--set", "u=1", "--stop", "1.05", "--step", "0.1",
                     "--output", "u_integral")
    ref = simulate_fmu(features, start_values={"u": 1.0}, stop_time=1.05, output_interval=0.1,
                       output=names)
    assert_same(ours, ref, names)
    assert ours["time"][-1] == 1.05


def test_vehicle_track_measured_profile_gives_fmpys_trajectory(tmp_path):
    vt = fmu_path("VehicleTrack")
    profile = tmp_path / "track.csv"
    with open(profile, "w") as f:
        f.write("x,z\n")
        for i in range(2001):
            x = -50 + 0.1 * i
            f.write(f"{x!r},{1e-3 * math.sin(2 * math.pi * x / 5.0)!r}\n")
    start = {"irregularity": 10, "profile_file": str(profile), "ramp_length": 0.0}
    names = ["Z0_1", "Zc_acc", "P1"]
    ours, _ = driver(vt, tmp_path, "--set", "irregularity=10", "--set",
                     f"profile_file={profile}", "--set", "ramp_length=0", "--stop", "0.2",
                     "--step", "0.001", *sum((["--output", n] for n in names), []))
    ref = simulate_fmu(vt, start_values=start, stop_time=0.2, output_interval=0.001,
                       output=names)
    assert_same(ours, ref, names)
    assert np.max(np.abs(ref["Z0_1"])) > 0.9e-3  # the profile reached the wheel
