"""fmpy cross-checks of Wheel.fmu: validation, accuracy against the closed form, parameter
rules, and memory stability over many load/run/unload cycles."""
import gc
import shutil
import tempfile

import numpy as np
import pytest
from fmpy import extract, read_model_description, simulate_fmu
from fmpy.fmi1 import FMICallException
from fmpy.fmi2 import FMU2Slave
from fmpy.validation import validate_fmu


def closed_form(t, m=10.0, k=100.0, c=20.0, q0=0.1):
    """Free response with q(0) = q0, q'(0) = 0 (underdamped regime), written independently."""
    w = np.sqrt(k / m)
    zeta = c / (2.0 * np.sqrt(k * m))
    assert zeta < 1.0
    wd = w * np.sqrt(1.0 - zeta**2)
    return q0 * np.exp(-zeta * w * t) * (np.cos(wd * t) + zeta * w / wd * np.sin(wd * t))


def test_validate_fmu_reports_no_problem(wheel_fmu):
    assert validate_fmu(wheel_fmu) == []


def test_model_description_declares_units_and_capabilities(wheel_fmu):
    md = read_model_description(wheel_fmu)
    assert md.fmiVersion == "2.0"
    cs = md.coSimulation
    assert cs.modelIdentifier == "Wheel"
    assert cs.canGetAndSetFMUstate and cs.canSerializeFMUstate
    variables = {v.name: v for v in md.modelVariables}
    assert variables["K"].variability == "tunable"
    assert variables["m"].variability == "fixed"
    assert variables["K"].unit == "N/m"
    assert [u.variable.name for u in md.outputs] == ["q", "v", "a"]


@pytest.mark.parametrize("k", [100.0, 90.0, 125.0])
def test_simulate_matches_closed_form(wheel_fmu, k):
    res = simulate_fmu(wheel_fmu, start_values={"K": k}, output_interval=0.01, stop_time=5.0)
    t = res["time"]
    assert len(t) == 501
    assert np.allclose(np.diff(t), 0.01)
    err = np.max(np.abs(res["q"] - closed_form(t, k=k)))
    assert err < 1e-8, err
    # q'' from the FMU satisfies the equation of motion at every output point.
    resid = 10.0 * res["a"] + 20.0 * res["v"] + k * res["q"]
    assert np.max(np.abs(resid)) < 1e-12


def _start(fmu, instantiate=True):
    """Instantiate (optionally), set up at t = 0 and leave initialization mode."""
    if instantiate:
        fmu.instantiate()
    fmu.setupExperiment(startTime=0.0)
    fmu.enterInitializationMode()
    fmu.exitInitializationMode()


def _slave(wheel_fmu, unzipdir):
    """Value references by name, and an FMU2Slave on the extracted FMU."""
    md = read_model_description(wheel_fmu)
    return {v.name: v.valueReference for v in md.modelVariables}, FMU2Slave(
        guid=md.guid,
        unzipDirectory=unzipdir,
        modelIdentifier=md.coSimulation.modelIdentifier,
        instanceName="wheel",
    )


def test_fixed_parameter_after_initialization_is_rejected(wheel_fmu):
    unzipdir = extract(wheel_fmu)
    try:
        vr, fmu = _slave(wheel_fmu, unzipdir)
        _start(fmu)
        with pytest.raises(FMICallException):
            fmu.setReal([vr["m"]], [5.0])
        fmu.reset()
        # After reset the fixed parameter may be set again, and it takes effect.
        fmu.setReal([vr["m"]], [40.0])
        _start(fmu, instantiate=False)
        fmu.doStep(0.0, 0.01)
        a = fmu.getReal([vr["a"]])[0]
        q, v = fmu.getReal([vr["q"], vr["v"]])
        assert abs(40.0 * a + 20.0 * v + 100.0 * q) < 1e-12
        fmu.terminate()
        fmu.freeInstance()
    finally:
        shutil.rmtree(unzipdir, ignore_errors=True)


def test_tunable_parameter_between_steps(wheel_fmu):
    unzipdir = extract(wheel_fmu)
    try:
        vr, fmu = _slave(wheel_fmu, unzipdir)
        _start(fmu)
        fmu.doStep(0.0, 0.5)
        fmu.setReal([vr["K"]], [200.0])
        assert fmu.getReal([vr["K"]])[0] == 200.0
        fmu.doStep(0.5, 0.01)
        q, v, a = fmu.getReal([vr["q"], vr["v"], vr["a"]])
        assert abs(10.0 * a + 20.0 * v + 200.0 * q) < 1e-12
        fmu.terminate()
        fmu.freeInstance()
    finally:
        shutil.rmtree(unzipdir, ignore_errors=True)


def _rss_kib():
    with open("/proc/self/status") as f:
        for line in f:
            if line.startswith("VmRSS:"):
                return int(line.split()[1])
    raise RuntimeError("no VmRSS")


def test_500_load_run_unload_cycles_keep_rss_flat(wheel_fmu):
    unzipdir = extract(wheel_fmu)
    md = read_model_description(wheel_fmu)
    vr_q = next(v.valueReference for v in md.modelVariables if v.name == "q")

    def cycle():
        fmu = FMU2Slave(guid=md.guid, unzipDirectory=unzipdir,
                        modelIdentifier="Wheel", instanceName="w")
        _start(fmu)
        t = 0.0
        for _ in range(50):
            fmu.doStep(t, 0.01)
            t += 0.01
        q = fmu.getReal([vr_q])[0]
        fmu.terminate()
        fmu.freeInstance()
        return q

    try:
        for _ in range(50):  # warm-up: allocator pools, ctypes caches
            cycle()
        gc.collect()
        before = _rss_kib()
        qs = {cycle() for _ in range(500)}
        gc.collect()
        after = _rss_kib()
        assert len(qs) == 1, "every cycle must give the same result"
        assert after - before < 4 * 1024, f"RSS grew by {after - before} KiB over 500 cycles"
    finally:
        shutil.rmtree(unzipdir, ignore_errors=True)
