"""The C test FMUs of uq-driver/tests/fmus (Functions, Features), cross-checked with fmpy.

The FMUs are built here by uq-driver/tests/fmus/build.py into $RAILUQ_TEST_FMU_DIR (default
target/test-fmu). Every reference value is computed in this file independently of the C code:
closed forms, Gauss quadrature written here, the documented hash re-implemented in Python, or
fmpy's own handling of inputs and early stops. A failing build is a failure, not a skip.
"""
import ctypes
import math
import os
import shutil
import signal
import subprocess
import sys
import textwrap
from contextlib import contextmanager
from statistics import NormalDist

import numpy as np
import pytest
from fmpy import extract, read_model_description, simulate_fmu
from fmpy.fmi1 import FMICallException
from fmpy.fmi2 import FMU2Slave, defaultCallbacks, fmi2LastSuccessfulTime, fmi2Terminated
from fmpy.validation import validate_fmu

from conftest import build_test_fmus

NAMES = ["Functions", "Features"]

FMI2_CS_FUNCTIONS = """
fmi2GetTypesPlatform fmi2GetVersion fmi2SetDebugLogging fmi2Instantiate fmi2FreeInstance
fmi2SetupExperiment fmi2EnterInitializationMode fmi2ExitInitializationMode fmi2Terminate
fmi2Reset fmi2GetReal fmi2GetInteger fmi2GetBoolean fmi2GetString fmi2SetReal fmi2SetInteger
fmi2SetBoolean fmi2SetString fmi2GetFMUstate fmi2SetFMUstate fmi2FreeFMUstate
fmi2SerializedFMUstateSize fmi2SerializeFMUstate fmi2DeSerializeFMUstate
fmi2GetDirectionalDerivative fmi2SetRealInputDerivatives fmi2GetRealOutputDerivatives
fmi2DoStep fmi2CancelStep fmi2GetStatus fmi2GetRealStatus fmi2GetIntegerStatus
fmi2GetBooleanStatus fmi2GetStringStatus
""".split()


# ------------------------------------------------------------------------------------------
# Building and driving the FMUs.

@pytest.fixture(scope="session")
def built():
    return build_test_fmus()


@pytest.fixture(scope="session")
def functions_fmu(built):
    return str(built["Functions"][0])


@pytest.fixture(scope="session")
def features_fmu(built):
    return str(built["Features"][0])


class Slave:
    """An instantiated FMU2Slave with value references by name."""

    def __init__(self, path, unzipdir):
        self.md = read_model_description(path)
        self.vars = {v.name: v for v in self.md.modelVariables}
        self.fmu = FMU2Slave(guid=self.md.guid, unzipDirectory=unzipdir,
                             modelIdentifier=self.md.coSimulation.modelIdentifier,
                             instanceName="test")
        self.fmu.instantiate()

    def vr(self, name):
        return self.vars[name].valueReference

    def set(self, **values):
        for name, value in values.items():
            kind = self.vars[name].type
            if kind == "Real":
                self.fmu.setReal([self.vr(name)], [float(value)])
            elif kind in ("Integer", "Enumeration"):
                self.fmu.setInteger([self.vr(name)], [int(value)])
            elif kind == "Boolean":
                self.fmu.setBoolean([self.vr(name)], [bool(value)])
            else:
                self.fmu.setString([self.vr(name)], [value])

    def get(self, name):
        kind = self.vars[name].type
        vr = [self.vr(name)]
        if kind == "Real":
            return self.fmu.getReal(vr)[0]
        if kind in ("Integer", "Enumeration"):
            return self.fmu.getInteger(vr)[0]
        if kind == "Boolean":
            return self.fmu.getBoolean(vr)[0]
        return self.fmu.getString(vr)[0].decode()

    def start(self, **values):
        """Set up at t = 0, set the values, initialize."""
        self.fmu.setupExperiment(startTime=0.0)
        self.set(**values)
        self.fmu.enterInitializationMode()
        self.fmu.exitInitializationMode()

    def evaluate(self, output, **values):
        """Reset, initialize with the values, return the output."""
        self.fmu.reset()
        self.start(**values)
        return self.get(output)


@contextmanager
def slave(path):
    unzipdir = extract(path)
    s = Slave(path, unzipdir)
    try:
        yield s
    finally:
        s.fmu.freeInstance()
        shutil.rmtree(unzipdir, ignore_errors=True)


# ------------------------------------------------------------------------------------------
# Both FMUs.

@pytest.mark.parametrize("name", NAMES)
def test_builds_without_compiler_warnings(built, name):
    assert built[name][1] == ""


@pytest.mark.parametrize("name", NAMES)
def test_validate_fmu_reports_no_problem(built, name):
    assert validate_fmu(str(built[name][0])) == []


@pytest.mark.parametrize("name", NAMES)
def test_binary_exports_the_34_co_simulation_functions(built, name):
    unzipdir = extract(str(built[name][0]))
    try:
        identifier = read_model_description(str(built[name][0])).coSimulation.modelIdentifier
        lib = ctypes.CDLL(os.path.join(unzipdir, "binaries", "linux64", identifier + ".so"))
        missing = [f for f in FMI2_CS_FUNCTIONS if not hasattr(lib, f)]
        assert len(FMI2_CS_FUNCTIONS) == 34
        assert missing == []
        lib.fmi2GetVersion.restype = ctypes.c_char_p
        assert lib.fmi2GetVersion() == b"2.0"
    finally:
        shutil.rmtree(unzipdir, ignore_errors=True)


def test_once_builds_cleanly_validates_and_refuses_an_interleaved_second_instance(built, capsys):
    # Once keeps its state in globals (canBeInstantiatedOnlyOncePerProcess): a step of an
    # instance other than the one last initialized fails instead of giving wrong numbers.
    path, warnings = built["Once"]
    assert warnings == ""
    assert validate_fmu(str(path)) == []
    unzipdir = extract(str(path))
    a = b = None
    try:
        a = Slave(str(path), unzipdir)
        a.start(x=2.0)
        a.fmu.doStep(0.0, 0.5)
        assert a.get("y") == pytest.approx(1.0, abs=1e-15)
        b = Slave(str(path), unzipdir)  # the same file: the same loaded library
        b.start(x=3.0)
        with pytest.raises(FMICallException):
            a.fmu.doStep(0.5, 0.5)
        assert "another instance of this library" in capsys.readouterr().out
    finally:
        for s in (b, a):
            if s is not None:
                s.fmu.freeInstance()
        shutil.rmtree(unzipdir, ignore_errors=True)


def _parse_start(variable):
    if variable.type == "Real":
        return float(variable.start)
    if variable.type in ("Integer", "Enumeration"):
        return int(variable.start)
    if variable.type == "Boolean":
        return variable.start in (True, "true", "1")
    return variable.start


@pytest.mark.parametrize("name", NAMES)
def test_start_values_in_the_model_description_are_the_values_of_the_c_code(built, name):
    with slave(str(built[name][0])) as s:
        s.fmu.setupExperiment(startTime=0.0)
        s.fmu.enterInitializationMode()
        with_start = [v for v in s.md.modelVariables if v.start is not None]
        assert len(with_start) >= 10
        for v in with_start:
            assert s.get(v.name) == _parse_start(v), v.name


@pytest.mark.parametrize("name, output", [("Functions", "y_t"), ("Features", "u_integral")])
def test_fmu_state_get_set_and_serialize_round_trip(built, name, output):
    with slave(str(built[name][0])) as s:
        s.start(**({"u": 2.0} if name == "Features" else {"x1": 1.0}))
        for i in range(5):
            s.fmu.doStep(i * 0.1, 0.1)
        state = s.fmu.getFMUstate()
        at_half = s.get(output)
        serialized = s.fmu.serializeFMUstate(state)
        for i in range(5, 10):
            s.fmu.doStep(i * 0.1, 0.1)
        assert s.get(output) != at_half
        s.fmu.setFMUstate(state)
        assert s.get(output) == at_half
        s.fmu.doStep(0.5, 0.1)
        restored = s.fmu.deSerializeFMUstate(serialized)
        s.fmu.setFMUstate(restored)
        assert s.get(output) == at_half
        assert s.get("time") == pytest.approx(0.5, abs=1e-15)
        s.fmu.freeFMUstate(state)
        s.fmu.freeFMUstate(restored)


@pytest.mark.parametrize("name", NAMES)
def test_illegal_call_sequences_are_refused_with_fmi2error(built, name, capsys):
    with slave(str(built[name][0])) as s:
        with pytest.raises(FMICallException) as e:
            s.fmu.doStep(0.0, 0.1)
        assert e.value.status == 3
        assert "illegal call" in capsys.readouterr().out
        s.fmu.reset()
        s.start()
        with pytest.raises(FMICallException):
            s.fmu.doStep(0.3, 0.1)  # the FMU is at t = 0
        assert "but the FMU is at t = 0" in capsys.readouterr().out
        s.fmu.reset()
        s.start()
        with pytest.raises(FMICallException):
            s.fmu.doStep(0.0, 0.0)
        assert "step size" in capsys.readouterr().out


# ------------------------------------------------------------------------------------------
# Functions: the formulas, written here independently.

def ishigami(x1, x2, x3, a=7.0, b=0.1):
    return np.sin(x1) + a * np.sin(x2) ** 2 + b * x3**4 * np.sin(x1)


def borehole(rw, r, Tu, Hu, Tl, Hl, L, Kw):
    lr = np.log(r / rw)
    return 2 * np.pi * Tu * (Hu - Hl) / (lr * (1 + 2 * L * Tu / (lr * rw**2 * Kw) + Tu / Tl))


G_A = [0.0, 1.0, 4.5, 9.0, 99.0, 99.0, 99.0, 99.0]


def g_function(x, a=G_A):
    return np.prod([(abs(4 * xi - 2) + ai) / (1 + ai) for xi, ai in zip(x, a)])


M64 = (1 << 64) - 1


def _splitmix64(state):
    state = (state + 0x9E3779B97F4A7C15) & M64
    z = state
    z = ((z ^ (z >> 30)) * 0xBF58476D1CE4E5B9) & M64
    z = ((z ^ (z >> 27)) * 0x94D049BB133111EB) & M64
    return state, z ^ (z >> 31)


def hashed_normal(seed):
    """The hash of the README: SplitMix64 from state = seed mod 2^64, then Box-Muller."""
    state, z1 = _splitmix64(seed & M64)
    _, z2 = _splitmix64(state)
    u1 = ((z1 >> 11) + 0.5) * 2.0**-53
    u2 = (z2 >> 11) * 2.0**-53
    return math.sqrt(-2.0 * math.log(u1)) * math.cos(2.0 * math.pi * u2)


BOREHOLE_RANGES = {"rw": (0.05, 0.15), "r": (100, 50000), "Tu": (63070, 115600),
                   "Hu": (990, 1110), "Tl": (63.1, 116), "Hl": (700, 820),
                   "L": (1120, 1680), "Kw": (9855, 12045)}


def test_linear_sum_and_sum_of_squares_at_random_points(functions_fmu):
    rng = np.random.default_rng(2)
    with slave(functions_fmu) as s:
        for x in rng.normal(size=(20, 8)):
            values = {f"x{i + 1}": v for i, v in enumerate(x)}
            assert s.evaluate("y", function=5, **values) == pytest.approx(x.sum(), rel=1e-14)
            assert s.evaluate("y", function=6, **values) == pytest.approx((x * x).sum(),
                                                                           rel=1e-14)


def test_product_at_random_lognormal_points(functions_fmu):
    rng = np.random.default_rng(3)
    with slave(functions_fmu) as s:
        for x in np.exp(rng.normal(scale=0.5, size=(20, 8))):
            values = {f"x{i + 1}": v for i, v in enumerate(x)}
            assert s.evaluate("y", function=7, **values) == pytest.approx(math.prod(x),
                                                                           rel=1e-14)


def test_twenty_input_g_function_at_random_points(functions_fmu):
    rng = np.random.default_rng(4)
    a = np.concatenate([[0.0, 0.5, 1.0, 2.0, 4.5, 9.0], np.full(14, 99.0)])
    with slave(functions_fmu) as s:
        for x in rng.uniform(size=(20, 20)):
            values = {f"x{i + 1}": v for i, v in enumerate(x)}
            coeffs = {f"a{i + 1}": v for i, v in enumerate(a)}
            want = np.prod((np.abs(4 * x - 2) + a) / (1 + a))
            assert s.evaluate("y", function=8, **values, **coeffs) == pytest.approx(
                want, rel=1e-14)
        # The default coefficients: a1..a8 as the eight-input g-function's, a9..a20 = 99.
        x = rng.uniform(size=20)
        a = np.array([0.0, 1.0, 4.5, 9.0] + [99.0] * 16)
        want = np.prod((np.abs(4 * x - 2) + a) / (1 + a))
        values = {f"x{i + 1}": v for i, v in enumerate(x)}
        assert s.evaluate("y", function=8, **values) == pytest.approx(want, rel=1e-14)


def test_ishigami_at_random_points(functions_fmu):
    rng = np.random.default_rng(1)
    with slave(functions_fmu) as s:
        for x in rng.uniform(-np.pi, np.pi, size=(50, 3)):
            y = s.evaluate("y", function=1, x1=x[0], x2=x[1], x3=x[2])
            assert y == pytest.approx(ishigami(*x), rel=1e-14, abs=1e-14)
        y = s.evaluate("y", function=1, x1=0.3, x2=-1.2, x3=2.0, a=5.0, b=0.2)
        assert y == pytest.approx(ishigami(0.3, -1.2, 2.0, a=5.0, b=0.2), rel=1e-14)


def test_ishigami_moments_and_sobol_indices_by_quadrature_match_the_closed_form(functions_fmu):
    """Gauss-Legendre (16 nodes per input) over U(-pi, pi)^3 through the FMU."""
    a, b = 7.0, 0.1
    nodes, weights = np.polynomial.legendre.leggauss(16)
    x, w = np.pi * nodes, weights / 2
    y = np.empty((16, 16, 16))
    with slave(functions_fmu) as s:
        for i in range(16):
            for j in range(16):
                for k in range(16):
                    y[i, j, k] = s.evaluate("y", function=1, x1=x[i], x2=x[j], x3=x[k])
    W = w[:, None, None] * w[None, :, None] * w[None, None, :]
    mean = np.sum(W * y)
    var = np.sum(W * (y - mean) ** 2)
    exact_var = a**2 / 8 + b * np.pi**4 / 5 + b**2 * np.pi**8 / 18 + 0.5
    assert mean == pytest.approx(a / 2, abs=1e-10)
    assert var == pytest.approx(exact_var, rel=1e-10)
    # First-order indices from the conditional means; total index of x3 from E[Var(y | x1, x2)].
    e1 = np.einsum("ijk,j,k->i", y, w, w)
    e2 = np.einsum("ijk,i,k->j", y, w, w)
    e3 = np.einsum("ijk,i,j->k", y, w, w)
    s1, s2, s3 = (np.sum(w * (e - mean) ** 2) / var for e in (e1, e2, e3))
    e12 = np.einsum("ijk,k->ij", y, w)
    st3 = np.sum(W * (y - e12[:, :, None]) ** 2) / var
    assert s1 == pytest.approx(0.5 * (1 + b * np.pi**4 / 5) ** 2 / exact_var, abs=1e-10)
    assert s2 == pytest.approx(a**2 / 8 / exact_var, abs=1e-10)
    assert abs(s3) < 1e-10
    assert st3 == pytest.approx(b**2 * np.pi**8 * (1 / 18 - 1 / 50) / exact_var, abs=1e-10)
    # Values measured with OpenTURNS on the same functions.
    assert (round(s1, 4), round(s2, 4), round(st3, 4)) == (0.3139, 0.4424, 0.2437)


def test_borehole_at_nominal_and_random_points(functions_fmu):
    rng = np.random.default_rng(2)
    with slave(functions_fmu) as s:
        nominal = {n: s.vars[n].start for n in BOREHOLE_RANGES}
        nominal = {n: float(v) for n, v in nominal.items()}
        assert nominal == {n: (lo + hi) / 2 for n, (lo, hi) in BOREHOLE_RANGES.items()}
        assert s.evaluate("y", function=2) == pytest.approx(borehole(**nominal), rel=1e-14)
        for _ in range(50):
            p = {n: rng.uniform(lo, hi) for n, (lo, hi) in BOREHOLE_RANGES.items()}
            assert s.evaluate("y", function=2, **p) == pytest.approx(borehole(**p), rel=1e-13)


def test_borehole_refuses_a_radius_outside_its_domain(functions_fmu, capsys):
    with slave(functions_fmu) as s:
        s.fmu.setupExperiment(startTime=0.0)
        s.set(function=2, rw=0.0)
        s.fmu.enterInitializationMode()
        with pytest.raises(FMICallException):
            s.fmu.exitInitializationMode()
    assert "0 < rw < r" in capsys.readouterr().out


def test_g_function_at_random_points_and_its_factors_integrate_to_the_closed_form(functions_fmu):
    rng = np.random.default_rng(3)
    with slave(functions_fmu) as s:
        for x in rng.uniform(0, 1, size=(50, 8)):
            xs = {f"x{i + 1}": v for i, v in enumerate(x)}
            assert s.evaluate("y", function=3, **xs) == pytest.approx(g_function(x), rel=1e-14)
        # Each factor alone (the others at x = 0.25, where a factor is 1), integrated exactly:
        # the factor is linear on [0, 1/2] and on [1/2, 1], so 2 Gauss nodes per half suffice
        # for its mean and its square.
        nodes, weights = np.polynomial.legendre.leggauss(2)
        xq = np.concatenate([0.25 + 0.25 * nodes, 0.75 + 0.25 * nodes])
        wq = np.concatenate([weights, weights]) / 4
        for i, a in enumerate(G_A):
            others = {f"x{j + 1}": 0.25 for j in range(8) if j != i}
            f = np.array([s.evaluate("y", function=3, **others, **{f"x{i + 1}": v}) for v in xq])
            mean = np.sum(wq * f)
            var = np.sum(wq * (f - mean) ** 2)
            assert mean == pytest.approx(1.0, abs=1e-14)
            assert var == pytest.approx(1 / (3 * (1 + a) ** 2), rel=1e-12)


def test_two_level_hash_is_the_documented_one(functions_fmu):
    seeds = [0, 1, 2, 5, 42, -1, -7, 1000, 123456789, 2**31 - 1, -(2**31)]
    with slave(functions_fmu) as s:
        for seed in seeds:
            h = s.evaluate("h_seed", function=4, seed=seed)
            assert h == pytest.approx(hashed_normal(seed), rel=1e-14, abs=1e-15), seed


def test_two_level_hash_gives_standard_normals(functions_fmu):
    n = 4000
    with slave(functions_fmu) as s:
        h = np.array([s.evaluate("h_seed", function=4, seed=seed) for seed in range(1, n + 1)])
    assert abs(h.mean()) < 4 / np.sqrt(n)
    assert abs(h.var() - 1) < 4 * np.sqrt(2 / n)
    # Kolmogorov-Smirnov distance to N(0, 1) below the 0.1 % critical value 1.95 / sqrt(n).
    cdf = np.array([NormalDist().cdf(v) for v in np.sort(h)])
    ks = max(np.max(np.arange(1, n + 1) / n - cdf), np.max(cdf - np.arange(n) / n))
    assert ks < 1.95 / np.sqrt(n)


def test_two_level_variance_split_matches_the_readme_closed_form(functions_fmu):
    """Outer: seeds 1..64 equally likely; inner: x1, x2 ~ N(0, 1) by 3-node Gauss-Hermite
    (exact for f_x = x1 + x2^2). README: E[y | seed] = 1 + sigma_h h(seed), Var(y | seed) = 3."""
    sigma_h = 1.5
    seeds = range(1, 65)
    nodes, weights = np.polynomial.hermite_e.hermegauss(3)
    weights = weights / weights.sum()
    cond_mean, cond_var = [], []
    with slave(functions_fmu) as s:
        for seed in seeds:
            y = np.array([[s.evaluate("y", function=4, seed=seed, sigma_h=sigma_h, x1=a, x2=b)
                           for b in nodes] for a in nodes])
            W = np.outer(weights, weights)
            m = np.sum(W * y)
            cond_mean.append(m)
            cond_var.append(np.sum(W * (y - m) ** 2))
    h = np.array([hashed_normal(seed) for seed in seeds])
    np.testing.assert_allclose(cond_mean, 1 + sigma_h * h, rtol=1e-13, atol=1e-13)
    np.testing.assert_allclose(cond_var, 3.0, rtol=1e-12)
    inner = np.mean(cond_var)
    outer = np.var(cond_mean)
    assert outer == pytest.approx(sigma_h**2 * np.var(h), rel=1e-12)
    fraction_inner = inner / (inner + outer)
    assert fraction_inner == pytest.approx(3 / (3 + sigma_h**2 * np.var(h)), rel=1e-12)


def test_y_t_is_y_times_one_plus_t_under_fmpy(functions_fmu):
    res = simulate_fmu(functions_fmu, start_values={"function": 4, "seed": 9, "x1": 0.5,
                                                     "x2": -2.0, "sigma_h": 2.0},
                       stop_time=2.0, output_interval=0.25)
    y = 0.5 + 4.0 + 2.0 * hashed_normal(9)
    np.testing.assert_allclose(res["y"], y, rtol=1e-14)
    np.testing.assert_allclose(res["y_t"], y * (1 + res["time"]), rtol=1e-14)
    np.testing.assert_allclose(res["f_x"], 4.5, rtol=1e-15)


@pytest.mark.parametrize("function", [0, 9, -1])
def test_an_unknown_function_is_refused_when_set(functions_fmu, function, capsys):
    with slave(functions_fmu) as s:
        with pytest.raises(FMICallException):
            s.set(function=function)
    assert "outside [1, 8]" in capsys.readouterr().out


# ------------------------------------------------------------------------------------------
# Features.

def test_parameters_of_every_type_are_read_back(features_fmu):
    start = {"int_param": -17, "bool_param": True, "enum_param": 3,
             "string_param": "grüße, 世界"}
    res = simulate_fmu(features_fmu, start_values=start, output_interval=0.5)
    assert list(res["int_out"]) == [-17] * 3
    assert list(res["bool_out"]) == [True] * 3
    assert list(res["enum_out"]) == [3] * 3
    assert list(res["string_len"]) == [len(start["string_param"].encode())] * 3
    with slave(features_fmu) as s:
        s.start(**start)
        assert s.get("string_out") == start["string_param"]
        assert (s.get("int_out"), s.get("bool_out"), s.get("enum_out")) == (-17, True, 3)


def test_input_signals_are_echoed_as_fmpy_applies_them(features_fmu):
    """fmpy sets the inputs at the start of each step: Real ones interpolated linearly, the others
    held, taking the value after an event at a repeated time. The FMU holds them over the step, so
    the outputs recorded at t_{n+1} show the inputs of t_n."""
    signal_ = np.array([(0.0, 0.0, 0, False), (0.5, 1.0, 2, False), (0.5, 1.0, 5, True),
                        (1.0, -2.0, 5, True)],
                       dtype=[("time", float), ("u", float), ("k", np.int32), ("flag", bool)])
    res = simulate_fmu(features_fmu, input=signal_, output_interval=0.1,
                       output=["u_echo", "u_integral", "k_echo", "flag_echo"])
    t = res["time"]
    assert len(t) == 11
    u_applied = np.interp(t[:-1], [0.0, 0.5, 1.0], [0.0, 1.0, -2.0])
    np.testing.assert_allclose(res["u_echo"][1:], u_applied, atol=1e-14)
    assert res["u_echo"][0] == 0.0
    np.testing.assert_allclose(res["u_integral"][1:], np.cumsum(u_applied * np.diff(t)),
                               atol=1e-14)
    after = t[:-1] >= 0.5 - 1e-12
    assert list(res["k_echo"][1:]) == list(np.where(after, 5, 0))
    assert list(res["flag_echo"][1:]) == list(after)


def test_read_file_from_the_resources_folder(features_fmu):
    res = simulate_fmu(features_fmu, output_interval=0.5)
    assert list(res["file_value"]) == [2.5e-3] * 3  # resources/value.txt


def test_read_file_absolute_path_skips_comments_and_words(features_fmu, tmp_path):
    path = tmp_path / "profile.txt"
    path.write_text("# 99 in a comment\ninformation: nan-free, x = -12.75e1 mm\n3\n")
    res = simulate_fmu(features_fmu, start_values={"read_file": str(path)}, output_interval=0.5)
    assert res["file_value"][-1] == -127.5
    res = simulate_fmu(features_fmu, start_values={"read_file": ""}, output_interval=0.5)
    assert res["file_value"][-1] == 0.0


def test_read_file_missing_fails_initialization_with_the_path(features_fmu, capsys):
    with pytest.raises(FMICallException):
        simulate_fmu(features_fmu, start_values={"read_file": "no/such.txt"})
    out = capsys.readouterr().out
    assert "cannot open" in out and "no/such.txt" in out


def test_resource_location_with_space_and_percent_is_decoded(features_fmu, tmp_path):
    unzipdir = tmp_path / "a b%20c ü"
    extract(features_fmu, unzipdir=str(unzipdir))
    res = simulate_fmu(str(unzipdir), output_interval=0.5)
    assert res["file_value"][-1] == 2.5e-3


@pytest.mark.parametrize("stop_at", [0.55, 0.5])
def test_stop_at_ends_the_fmpy_run_there(features_fmu, stop_at):
    res = simulate_fmu(features_fmu, start_values={"stop_at": stop_at, "u": 2.0},
                       stop_time=2.0, output_interval=0.1)
    assert res["time"][-1] == pytest.approx(stop_at, abs=1e-12)
    assert np.all(np.diff(res["time"]) > 0)
    assert res["u_integral"][-1] == pytest.approx(2.0 * stop_at, abs=1e-12)


def test_stop_at_status_as_an_importer_sees_it(features_fmu, capsys):
    with slave(features_fmu) as s:
        s.start(stop_at=0.25)
        s.fmu.doStep(0.0, 0.2)
        assert not s.fmu.getBooleanStatus(fmi2Terminated)
        with pytest.raises(FMICallException) as e:
            s.fmu.doStep(0.2, 0.2)
        assert e.value.status == 2  # fmi2Discard
        assert s.fmu.getBooleanStatus(fmi2Terminated)
        assert s.fmu.getRealStatus(fmi2LastSuccessfulTime) == 0.25
        assert s.get("time") == 0.25
        with pytest.raises(FMICallException) as e:
            s.fmu.doStep(0.25, 0.1)
        assert e.value.status == 3
        assert "illegal call" in capsys.readouterr().out


def test_misbehave_1_is_an_fmpy_exception_with_the_log_message(features_fmu, capsys):
    with pytest.raises(FMICallException) as e:
        simulate_fmu(features_fmu, start_values={"misbehave": 1, "misbehave_at": 0.3},
                     output_interval=0.1)
    assert e.value.status == 3
    assert "misbehave = 1: fmi2DoStep fails on purpose at t = 0.3" in capsys.readouterr().out


def test_misbehave_6_gives_nan_outputs_from_misbehave_at(features_fmu):
    res = simulate_fmu(features_fmu, start_values={"misbehave": 6, "misbehave_at": 0.3, "u": 1.0},
                       output_interval=0.1)
    late = res["time"] >= 0.3 - 1e-12
    assert np.all(np.isnan(res["u_echo"][late])) and np.all(np.isnan(res["u_integral"][late]))
    assert not np.any(np.isnan(res["u_integral"][~late]))
    assert list(res["int_out"]) == [3] * len(res)


def test_misbehave_7_fatal_and_8_warning(features_fmu, capsys):
    with pytest.raises(FMICallException) as e:
        simulate_fmu(features_fmu, start_values={"misbehave": 7}, output_interval=0.1)
    assert e.value.status == 4
    res = simulate_fmu(features_fmu, start_values={"misbehave": 8, "u": 1.0}, output_interval=0.1)
    assert res["time"][-1] == pytest.approx(1.0)
    assert res["u_integral"][-1] == pytest.approx(1.0)
    out = capsys.readouterr().out
    assert "fatal error on purpose" in out and "a warning on purpose" in out


def test_misbehave_13_fails_above_the_bound_read_from_a_file(features_fmu, tmp_path, capsys):
    bound = tmp_path / "bound.txt"
    bound.write_text("2.5\n")
    start = {"misbehave": 13, "misbehave_at": 0.3, "u": 1.0, "read_file": str(bound)}
    res = simulate_fmu(features_fmu, start_values={**start, "gain": 2.5}, output_interval=0.1)
    assert res["time"][-1] == pytest.approx(1.0)
    assert res["u_gain"][-1] == pytest.approx(2.5)
    with pytest.raises(FMICallException):
        simulate_fmu(features_fmu, start_values={**start, "gain": 2.6}, output_interval=0.1)
    assert "misbehave = 13: gain = 2.6 is above file_value = 2.5" in capsys.readouterr().out
    bound.write_text("3\n")
    res = simulate_fmu(features_fmu, start_values={**start, "gain": 2.6}, output_interval=0.1)
    assert res["u_gain"][-1] == pytest.approx(2.6)


RUN_IN_CHILD = textwrap.dedent("""
    import sys
    from fmpy import simulate_fmu
    print("simulating", flush=True)
    simulate_fmu(sys.argv[1], start_values={"misbehave": int(sys.argv[2])}, output_interval=0.1)
    print("finished", flush=True)
""")


@pytest.mark.parametrize("misbehave, expect", [(2, -signal.SIGSEGV), (3, -signal.SIGABRT),
                                               (4, 0), (5, "blocks")])
def test_misbehave_2_to_5_crash_exit_or_hang_the_importer_process(features_fmu, misbehave,
                                                                  expect):
    """fmpy in a child process: what uq-driver's --isolate must survive. The child says when
    fmpy is imported and the simulation starts; the misbehaviour comes microseconds later."""
    proc = subprocess.Popen([sys.executable, "-c", RUN_IN_CHILD, features_fmu, str(misbehave)],
                            stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
    try:
        assert proc.stdout.readline() == "simulating\n"
        if expect == "blocks":
            with pytest.raises(subprocess.TimeoutExpired):
                proc.wait(timeout=2)
            return
        assert proc.wait(timeout=30) == expect, proc.stderr.read()
        rest = proc.stdout.read()
        # Never "finished": exit(0) ends the importer silently; the FMU's warning comes first.
        assert "finished" not in rest
        assert f"misbehave = {misbehave}:" in rest
    finally:
        proc.kill()
        proc.wait()
        proc.stdout.close()
        proc.stderr.close()


def test_setting_rules(features_fmu, capsys):
    with slave(features_fmu) as s:
        s.start()
        s.fmu.doStep(0.0, 0.1)
        s.set(u=3.0, k=4, flag=True)  # inputs may change between steps
        assert (s.get("u_echo"), s.get("k_echo"), s.get("flag_echo")) == (3.0, 4, True)
        assert s.get("u_gain") == 3.0
        s.set(gain=-0.5)  # and tunable parameters
        assert s.get("u_gain") == -1.5
        s.fmu.doStep(0.1, 0.1)
        assert s.get("u_gain") == -1.5
        with pytest.raises(FMICallException):
            s.set(int_param=1)
        assert "fixed parameter" in capsys.readouterr().out
        s.fmu.reset()
        with pytest.raises(FMICallException):
            s.set(u_echo=1.0)
        assert "is an output" in capsys.readouterr().out
        s.fmu.reset()
        with pytest.raises(FMICallException):
            s.set(string_param="x" * 1024)
        assert "at most 1023 allowed" in capsys.readouterr().out
        s.fmu.reset()
        s.set(string_param="x" * 1023)
        for value, var in [(4, "enum_param"), (0, "enum_param"), (14, "misbehave")]:
            s.fmu.reset()
            with pytest.raises(FMICallException):
                s.set(**{var: value})
            assert "is outside" in capsys.readouterr().out


@pytest.mark.parametrize("name", NAMES)
def test_instantiate_refuses_a_wrong_guid_and_model_exchange(built, name, capsys):
    path = str(built[name][0])
    md = read_model_description(path)
    unzipdir = extract(path)
    try:
        wrong = FMU2Slave(guid="{not-the-guid}", unzipDirectory=unzipdir,
                          modelIdentifier=md.coSimulation.modelIdentifier, instanceName="w")
        with pytest.raises(Exception, match="instantiate"):
            wrong.instantiate()
        assert "wrong GUID {not-the-guid}" in capsys.readouterr().out
        lib = ctypes.CDLL(os.path.join(unzipdir, "binaries", "linux64",
                                       md.coSimulation.modelIdentifier + ".so"))
        lib.fmi2Instantiate.restype = ctypes.c_void_p
        model_exchange = 0
        assert lib.fmi2Instantiate(b"x", model_exchange, md.guid.encode(), b"file:///tmp",
                                   ctypes.byref(defaultCallbacks), 0, 0) is None
        assert "only Co-Simulation is supported (fmuType = 0)" in capsys.readouterr().out
    finally:
        shutil.rmtree(unzipdir, ignore_errors=True)
