"""Vehicle.fmu against an independent reference model (vehicle_reference.py, written from
MODELS.md section 5 without reading the Rust implementation): the linear critical speed, the
steady wheel forces on a curve, and the documented effect of the roll moment that the FMU leaves
out, and the FMU's `roll_moment = 1`, which adds it. All run on the RSGEO contact table."""
import numpy as np
import pytest
from fmpy import simulate_fmu

from conftest import ROOT, fmu_path
from vehicle_reference import PARAMETERS, WHEELS, Car, hopf_speed

RSGEO = str(ROOT / "tests" / "data" / "rsgeo_s1002_uic60_1in40.csv")

# The steady curve: radius [m], speed [m/s], cant [rad]; the FMU enters it over a 3 s transition
# and runs until the car body has settled: it creeps for tens of seconds (the 5 s means of Q
# move by 0.07 % from 20 s to 40 s; a 25 s run fails the settling check below), by 120 s the
# last two 5 s means differ by 0.15 N at most.
CURVE_R, CURVE_V, CURVE_CANT = 1000.0, 30.0, 0.05
TRANSITION, RUN, WINDOW = 3.0, 120.0, 5.0  # [s]
FORCES = [f"{q}_{w}" for q in ("Y", "Q") for w in WHEELS]
OUTPUTS = FORCES + [f"dQQ_{w}" for w in WHEELS]
MASS = PARAMETERS["m_c"] + 2 * PARAMETERS["m_b"] + 4 * PARAMETERS["m_w"]  # [kg]
Q_STATIC = MASS * PARAMETERS["g"] / 8  # [N]


@pytest.fixture(scope="module")
def vehicle_fmu():
    return fmu_path("Vehicle")


def run_curve(vehicle_fmu, roll_moment):
    """The FMU's wheel forces on the curve with its parameter `roll_moment`: the means over the
    last WINDOW seconds of the run, and over the WINDOW before that (to see that the run has
    settled)."""
    r = simulate_fmu(vehicle_fmu, stop_time=RUN, output_interval=0.05, output=OUTPUTS,
                     start_values=dict(contact_table=RSGEO, v=CURVE_V, R=CURVE_R,
                                       cant=CURVE_CANT, transition=TRANSITION, y0_w1=0.0,
                                       y0_w3=0.0, roll_moment=roll_moment))
    last = r["time"] > RUN - WINDOW
    before = (r["time"] > RUN - 2 * WINDOW) & ~last
    return ({k: float(r[k][last].mean()) for k in OUTPUTS},
            {k: float(r[k][before].mean()) for k in OUTPUTS})


@pytest.fixture(scope="module")
def fmu_curve(vehicle_fmu):
    """The FMU as the reference implementation takes it (`roll_moment` = 0, the default)."""
    return run_curve(vehicle_fmu, 0)


def reference_curve(roll_lateral_moment):
    """The reference's quasi-static wheel forces on the curve."""
    car = Car(RSGEO, roll_lateral_moment=roll_lateral_moment)
    car.v = CURVE_V
    x, residual = car.curve_equilibrium(CURVE_R, CURVE_CANT)
    assert residual < 1e-8
    return car.wheel_forces(x)


def test_linear_critical_speed_on_rsgeo_table_matches_reference_hopf_speed(vehicle_fmu):
    r = simulate_fmu(vehicle_fmu, stop_time=0.01, output_interval=0.005,
                     output=["v_cr_linear"],
                     start_values=dict(contact_table=RSGEO, y0_w1=0.0, y0_w3=0.0))
    fmu = float(r["v_cr_linear"][-1])
    reference = hopf_speed(Car(RSGEO))
    # Measured: FMU 109.006 m/s, reference 108.992 m/s (-0.013 %). The FMU with the built-in
    # table gives 50.85 m/s, with k2 + 5 % 110.93 m/s (+1.8 %), with D6 + 5 % 109.21 m/s
    # (+0.19 %): each fails (k1 + 5 % moves it by less than 0.1 % and passes).
    assert reference == pytest.approx(fmu, rel=1e-3)


def test_steady_curve_wheel_forces_match_reference_and_sum_to_mass_times_acceleration(
        fmu_curve):
    fmu, before = fmu_curve
    # The FMU's run has settled: between the last two windows the means moved by at most
    # 0.15 N (measured; 2e-6 of Q, 1e-5 of Y), bound 0.67 N.
    for k in FORCES:
        assert abs(fmu[k] - before[k]) < 1e-5 * Q_STATIC, k
    reference = reference_curve(roll_lateral_moment=False)
    for w in WHEELS:
        # Q (60-74 kN) measured within 0.00013 % (0.08 N).
        assert reference["Q_" + w] == pytest.approx(fmu["Q_" + w], rel=1e-3), w
        # Y (1.5-3.9 kN) measured within 0.0105 % (0.33 N): the same 0.1 % keeps a margin of
        # ten and still fails the reference with the lateral forces' roll moment (Y 1.3-2.8 %
        # off, Q 1.8-3.0 %). The FMU with k1, k2 or the cant + 5 % fails too (k5 + 5 % hardly
        # moves the steady forces and passes).
        assert reference["Y_" + w] == pytest.approx(fmu["Y_" + w], rel=1e-3), w
    # Quasi-static balance across the track: the wheels' lateral forces carry the whole car's
    # uncompensated lateral acceleration, 22 191.5 N (measured: FMU +0.0008 %, reference
    # 4e-11, its equilibrium's residual).
    a_nc = CURVE_V**2 / CURVE_R * np.cos(CURVE_CANT) - PARAMETERS["g"] * np.sin(CURVE_CANT)
    for forces in (fmu, reference):
        assert sum(forces["Y_" + w] for w in WHEELS) == pytest.approx(MASS * a_nc, rel=5e-3)


def test_fmu_inner_wheel_unloading_is_below_a_model_with_the_lateral_forces_roll_moment(
        fmu_curve):
    fmu, _ = fmu_curve
    reference = reference_curve(roll_lateral_moment=True)
    for w in WHEELS[1::2]:  # the right (inner) wheels
        unloading = (Q_STATIC - reference["Q_" + w]) / Q_STATIC
        ratio = unloading / fmu["dQQ_" + w]
        # Measured ratios 1.194 (leading wheelsets 1, 3: 0.123 against the FMU's 0.103) and
        # 1.270 (trailing 2, 4: 0.128 against 0.101), the FMU's unloading 16-21 % below: the
        # documented "about 20 % below". Bounds 0.04 below and 0.08 above the measured.
        assert 1.15 <= ratio <= 1.35, (w, ratio)


def test_roll_moment_1_matches_the_reference_with_the_lateral_forces_roll_moment(vehicle_fmu):
    fmu, before = run_curve(vehicle_fmu, 1)
    for k in FORCES:
        assert abs(fmu[k] - before[k]) < 1e-5 * Q_STATIC, k
    reference = reference_curve(roll_lateral_moment=True)
    for k in FORCES:
        # Measured (150 s runs): Q within 0.001 %, Y within 0.01 %; the reference without the
        # moment is 1.3-3.0 % off, as above.
        assert reference[k] == pytest.approx(fmu[k], rel=1e-3), k
