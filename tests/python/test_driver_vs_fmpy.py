"""uq-driver loads the FMU through its own C-ABI importer; fmpy through ctypes. For the same
parameter values both must give the same trajectory (to 1e-12)."""
import subprocess

import numpy as np
import pytest
from fmpy import simulate_fmu

from conftest import DRIVER, ROOT, fmu_path


def driver_simulate(fmu, values, stop, step, tmp_path, outputs=()):
    out = tmp_path / "traj.csv"
    cmd = [str(DRIVER), "simulate", fmu, "--stop", str(stop), "--step", str(step), "--out", str(out)]
    for k, v in values.items():
        cmd += ["--set", f"{k}={v}" if isinstance(v, str) else f"{k}={v!r}"]
    for o in outputs:
        cmd += ["--output", o]
    if not DRIVER.is_file():
        pytest.fail(f"{DRIVER} is missing: run `make build` first")
    subprocess.run(cmd, check=True, capture_output=True, text=True)
    return np.genfromtxt(out, delimiter=",", names=True)


def both_simulate(fmu, values, stop, step, tmp_path, outputs):
    """The same run by uq-driver and by fmpy: (ours, fmpy's)."""
    ours = driver_simulate(fmu, values, stop, step, tmp_path, outputs)
    ref = simulate_fmu(fmu, start_values=values, output_interval=step, stop_time=stop,
                       output=list(outputs))
    return ours, ref


def assert_close(ours, ref, outputs, floor):
    """Each of `outputs` within 1e-12 of fmpy's, relative to its largest value (at least
    `floor`)."""
    for name in outputs:
        scale = max(floor, np.max(np.abs(ref[name])))
        assert np.max(np.abs(ours[name] - ref[name])) <= 1e-12 * scale, name


@pytest.mark.parametrize(
    "values",
    [{"K": 100.0, "C": 20.0}, {"K": 83.1, "C": 23.7}, {"K": 121.4, "C": 15.2}],
)
def test_wheel_trajectory_matches_fmpy(wheel_fmu, values, tmp_path):
    ours = driver_simulate(wheel_fmu, values, 5.0, 0.01, tmp_path)
    ref = simulate_fmu(wheel_fmu, start_values=values, output_interval=0.01, stop_time=5.0)
    assert len(ours) == len(ref) == 501
    assert np.max(np.abs(ours["time"] - ref["time"])) < 1e-12
    for name in ("q", "v", "a"):
        assert np.max(np.abs(ours[name] - ref[name])) <= 1e-12, name


def test_bogie_trajectory_matches_fmpy(tmp_path):
    bogie = fmu_path("Bogie")
    values = {"K_sy": 1.9e5, "C_sy": 2.7e4, "K_phi": 2.6e6}
    outputs = ("Y", "phi", "V", "F_T")
    ours, ref = both_simulate(bogie, values, 60.0, 0.01, tmp_path, outputs)
    assert_close(ours, ref, outputs, 1.0)


def test_vehicle_track_trajectory_matches_fmpy(tmp_path):
    vt = fmu_path("VehicleTrack")
    values = {"Kpz": 1.6e6, "Csz": 1.3e5, "dip_depth": 3e-4, "irregularity": 3}
    outputs = ("Zc_acc", "P1", "Zw1", "Zr1")
    ours, ref = both_simulate(vt, values, 0.5, 0.001, tmp_path, outputs)
    assert len(ours) == len(ref) == 501
    assert_close(ours, ref, outputs, 1e-12)
    # The dip makes an impact: the leading wheel's force rises well above the static load.
    assert np.max(ref["P1"]) > 1.2 * 69.0e3


def test_bogie_run_past_the_speed_limit_ends_early_and_both_keep_the_rows(tmp_path):
    # V0 = 10 m/s, ramp 1 s2/m: V = 10 - t reaches the 1 m/s limit at t = 9 s. The FMU ends the
    # simulation there (fmi2Discard, fmi2Terminated true, last successful time 8.9 s) instead of
    # returning fmi2Error: fmpy keeps the result up to 8.9 s (before, it raised and kept
    # nothing), and uq-driver's simulate writes the same rows.
    bogie = fmu_path("Bogie")
    values = {"V0": 10.0, "ramp": 1.0}
    outputs = ("Y", "V")
    ours, ref = both_simulate(bogie, values, 12.0, 0.1, tmp_path, outputs)
    assert abs(ref["time"][-1] - 8.9) < 1e-9, ref["time"][-1]
    # fmpy records the last successful time once more after the discarded step.
    if ref["time"][-1] == ref["time"][-2]:
        ref = ref[:-1]
    assert len(ours) == len(ref) == 90
    assert np.max(np.abs(ours["time"] - ref["time"])) < 1e-12
    for name in outputs:
        assert np.max(np.abs(ours[name] - ref[name])) <= 1e-12, name
    assert abs(ref["V"][-1] - 1.1) < 1e-9


def test_vehicle_trajectory_matches_fmpy(tmp_path):
    car = fmu_path("Vehicle")
    values = {"v": 60.0, "k4": 1.9e5, "D6": 1.5e5, "irregularity": 3, "seed": 7}
    outputs = ("y_w1", "Y_1L", "Q_1L", "YQ_1L", "SumY_1", "ay_floor_1", "speed")
    ours, ref = both_simulate(car, values, 2.0, 0.01, tmp_path, outputs)
    assert len(ours) == len(ref) == 201
    assert_close(ours, ref, outputs, 1e-12)
    assert np.all(ref["speed"] == 60.0)
    # The irregular track excites the car: the wheel loads vary by more than 1 %.
    assert np.ptp(ref["Q_1L"][50:]) > 0.01 * np.mean(ref["Q_1L"])


def test_vehicle_reads_a_contact_table_file_like_its_built_in_one(tmp_path):
    # The built-in table is the one `railuq-fmu contact --smooth 0.05` writes (S1002 on UIC60
    # at 1:40, computed from the profiles and smoothed over 0.05 mm): the same table read from
    # that file must give the same run, bit for bit.
    car = fmu_path("Vehicle")
    table = str(tmp_path / "builtin.csv")
    tool = ROOT / "target" / "release" / "railuq-fmu"
    subprocess.run([str(tool), "contact", "--smooth", "0.05", "--out", table], check=True,
                   capture_output=True)
    outputs = ["y_w3", "Y_3L", "Q_3R"]
    built_in = simulate_fmu(car, start_values={"v": 50.0}, output_interval=0.01, stop_time=1.0,
                            output=outputs)
    from_file = simulate_fmu(car, start_values={"v": 50.0, "contact_table": table},
                             output_interval=0.01, stop_time=1.0, output=outputs)
    for name in outputs:
        assert np.array_equal(built_in[name], from_file[name]), name
    ours = driver_simulate(car, {"v": 50.0, "contact_table": table}, 1.0, 0.01, tmp_path,
                           outputs)
    for name in outputs:
        assert np.array_equal(ours[name], from_file[name]), name


def test_vehicle_derailment_ends_the_run_and_both_keep_the_rows(tmp_path):
    # A 300 m curve without cant at 45 m/s: the car derails; fmi2DoStep discards and both
    # importers keep the rows up to the last successful step.
    car = fmu_path("Vehicle")
    values = {"v": 45.0, "R": 300.0, "y0_w3": 0.0}
    outputs = ("y_w1", "Y_1L")
    ours, ref = both_simulate(car, values, 10.0, 0.01, tmp_path, outputs)
    if ref["time"][-1] == ref["time"][-2]:
        ref = ref[:-1]
    assert ref["time"][-1] < 9.0, "derailed well before the stop time"
    assert len(ours) == len(ref)
    assert_close(ours, ref, outputs, 0.0)
