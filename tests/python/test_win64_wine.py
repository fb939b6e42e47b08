"""The win64 DLL of the FMUs, run for real: a small FMI importer in C (tests/wine/importer.c),
built with mingw-w64, loads it under Wine (Debian's wine64), steps the Wheel and is compared
with the closed form and with the linux64 binary run by fmpy (Bogie, VehicleTrack, Vehicle too, and
VehicleTrack reading a measured profile from its resources folder, given as a file:///Z:/...
URI); calls in the wrong state must return fmi2Error.

Debian 12's Wine 8.0 lacks bcryptprimitives.dll, which Rust's standard library imports on
Windows (every Windows 10 or later has it): a stand-in built from tests/wine/bcryptprimitives.c
sits beside the importer, for this test only.

Where mingw-w64 or Wine cannot be had, or the FMUs carry no win64 binary (`make test` installs
the toolchain as root), the tests are skipped with the reason, except under CI (env CI set),
where that is a failure."""
import os
import pathlib
import shutil
import subprocess

import numpy as np
import pytest
from fmpy import extract, read_model_description
from fmpy.fmi2 import FMU2Slave

import fmpy
from binaries import PE
from conftest import ROOT, fmu_path

TOOLCHAIN = ROOT / "tests" / "wine" / "toolchain.sh"
WINE_DIR = ROOT / "tests" / "wine"
MINGW_GCC = "x86_64-w64-mingw32-gcc"
WINE_TIMEOUT = 300  # s; the first run creates the Wine prefix
# The 34 functions of an FMI 2.0 Co-Simulation binary (FMI 2.0.4, sections 2.1 and 4.2).
FMI2_CS_FUNCTIONS = sorted("fmi2" + f for f in """
    GetTypesPlatform GetVersion SetDebugLogging Instantiate FreeInstance SetupExperiment
    EnterInitializationMode ExitInitializationMode Terminate Reset GetReal GetInteger GetBoolean
    GetString SetReal SetInteger SetBoolean SetString GetFMUstate SetFMUstate FreeFMUstate
    SerializedFMUstateSize SerializeFMUstate DeSerializeFMUstate GetDirectionalDerivative
    SetRealInputDerivatives GetRealOutputDerivatives DoStep CancelStep GetStatus GetRealStatus
    GetIntegerStatus GetBooleanStatus GetStringStatus""".split())
FMI2_ERROR = 3


def in_ci():
    return os.environ.get("CI", "").strip().lower() not in ("", "0", "false", "no")


def unavailable(message):
    if in_ci():
        pytest.fail(message + " (CI is set: this is a failure, not a skip)")
    pytest.skip(message)


def toolchain(command):
    p = subprocess.run(["bash", str(TOOLCHAIN), command], capture_output=True, text=True)
    return p.returncode == 0, (p.stdout.strip() if p.returncode == 0 else p.stderr.strip())


def windows_path(path):
    """Wine's default prefix maps drive Z: to the root of the Unix file system."""
    return "Z:" + str(path).replace("/", "\\")


class Wine:
    def __init__(self, program, folder, env):
        self.program, self.folder, self.env = program, folder, env

    def importer(self, fmu_dir, md, *args):
        """Runs the importer on the win64 DLL of the FMU extracted in fmu_dir; returns stdout."""
        dll = pathlib.Path(fmu_dir) / "binaries" / "win64" / f"{md.coSimulation.modelIdentifier}.dll"
        uri = "file:///" + windows_path(pathlib.Path(fmu_dir) / "resources").replace("\\", "/")
        cmd = [self.program, str(self.folder / "importer.exe"), windows_path(dll), md.guid, uri,
               *map(str, args)]
        p = subprocess.run(cmd, capture_output=True, text=True, env=self.env,
                           timeout=WINE_TIMEOUT)
        if p.returncode != 0:
            pytest.fail(f"importer exited {p.returncode}:\n{p.stdout[-2000:]}\n{p.stderr[-3000:]}")
        return p.stdout


@pytest.fixture(scope="module")
def wheel():
    """(extracted folder, model description) of Wheel.fmu, with its win64 binary."""
    fmu = extracted("Wheel")
    yield fmu
    shutil.rmtree(fmu[0], ignore_errors=True)


@pytest.fixture(scope="module")
def wine(tmp_path_factory):
    ok, program = toolchain("check-wine")
    if not ok:
        unavailable(f"cannot run Windows programs here: {program}")
    if shutil.which(MINGW_GCC) is None:
        unavailable(f"{MINGW_GCC} is missing (Debian: apt-get install gcc-mingw-w64-x86-64)")
    folder = tmp_path_factory.mktemp("wine")
    headers = pathlib.Path(fmpy.__file__).parent / "c-code"
    flags = ["-O2", "-Wall", "-Wextra", "-Werror"]
    builds = [
        # mingw's own printf, so that "%.17g" round-trips every double.
        ["-std=c11", "-D__USE_MINGW_ANSI_STDIO=1", f"-I{headers}", "-o",
         folder / "importer.exe", WINE_DIR / "importer.c"],
        ["-shared", "-o", folder / "bcryptprimitives.dll", WINE_DIR / "bcryptprimitives.c",
         "-ladvapi32"],
    ]
    for b in builds:
        p = subprocess.run([MINGW_GCC, *flags, *map(str, b)], capture_output=True, text=True)
        assert p.returncode == 0, p.stderr
    prefix = ROOT / "target" / "wine-prefix"
    env = dict(os.environ, WINEPREFIX=str(prefix), WINEDEBUG="-all",
               WINEDLLOVERRIDES="mscoree,mshtml=")
    env.pop("DISPLAY", None)
    beside = pathlib.Path(program).with_name("wineserver")
    server = str(beside) if os.access(beside, os.X_OK) else shutil.which("wineserver")
    if server is None:
        unavailable(f"no wineserver beside {program} nor on PATH")
    quiet = dict(env=env, stdin=subprocess.DEVNULL, stdout=subprocess.DEVNULL,
                 stderr=subprocess.DEVNULL, timeout=WINE_TIMEOUT)
    # One persistent wineserver and the prefix's services for the whole module, started with
    # no pipe of ours: each importer run then starts in well under a second, and no service
    # it would start keeps our pipes open until it exits.
    prefix.mkdir(parents=True, exist_ok=True)
    subprocess.run([server, "-p"], **quiet, check=True)
    try:
        subprocess.run([program, "wineboot", "--init"], **quiet, check=True)
        yield Wine(program, folder, env)
    finally:
        subprocess.run([server, "-k"], **quiet)


def closed_form(t, m, k, c, q0):
    """q and q' of m q'' + c q' + k q = 0, q(0) = q0, q'(0) = 0 (underdamped), by hand."""
    w = np.sqrt(k / m)
    zeta = c / (2.0 * np.sqrt(k * m))
    assert zeta < 1.0
    wd = w * np.sqrt(1.0 - zeta**2)
    decay = np.exp(-zeta * w * t)
    q = q0 * decay * (np.cos(wd * t) + zeta * w / wd * np.sin(wd * t))
    v = -q0 * w**2 / wd * decay * np.sin(wd * t)
    return q, v


def refs(md):
    return {v.name: v.valueReference for v in md.modelVariables}


def extracted(name):
    """(extracted folder, model description) of <name>.fmu, which must carry win64."""
    path = fmu_path(name)
    folder = extract(path)
    if not (pathlib.Path(folder) / "binaries" / "win64" / f"{name}.dll").is_file():
        shutil.rmtree(folder, ignore_errors=True)
        ok, why = toolchain("check-build")
        unavailable(f"{name}.fmu carries no win64 binary" + ("" if ok else f" ({why})"))
    return folder, read_model_description(path)


def run_under_wine(wine, fmu, sets, outputs, stop, dt):
    """[t, outputs...] at t_i = i dt from the win64 binary, run by the importer under Wine."""
    folder, md = fmu
    vr = refs(md)
    kinds = {v.name: v.type for v in md.modelVariables}
    prefix = {"Real": "", "Integer": "i:", "String": "s:"}
    set_arg = ",".join(f"{prefix[kinds[n]]}{vr[n]}={x}" for n, x in sets.items()) or "-"
    get_arg = ",".join(str(vr[n]) for n in outputs)
    out = wine.importer(folder, md, "run", stop, dt, set_arg, get_arg)
    lines = out.splitlines()
    header = dict(line.split(" ", 1) for line in lines if not line[:1].isdigit())
    assert header == {"exports-missing": "0", "version": "2.0", "types-platform": "default"}
    rows = np.array([[float(x) for x in line.split(",")] for line in lines if line[:1].isdigit()])
    assert rows.shape == (round(stop / dt) + 1, len(outputs) + 1)
    return rows


def run_linux_so(name, sets, outputs, stop, dt, resources=None):
    """The same calls on the linux64 binary through fmpy, at the same communication points;
    `resources` ({file name: text}) are written to the FMU's resources folder first."""
    path = fmu_path(name)
    md = read_model_description(path)
    vr = refs(md)
    kinds = {v.name: v.type for v in md.modelVariables}
    folder = extract(path)
    try:
        write_resources(folder, resources or {})
        fmu = FMU2Slave(guid=md.guid, unzipDirectory=folder,
                        modelIdentifier=md.coSimulation.modelIdentifier, instanceName="linux")
        fmu.instantiate()
        setters = {"Real": fmu.setReal, "Integer": fmu.setInteger, "String": fmu.setString}
        for n, x in sets.items():
            setters[kinds[n]]([vr[n]], [x])
        fmu.setupExperiment(startTime=0.0, stopTime=stop)
        fmu.enterInitializationMode()
        fmu.exitInitializationMode()
        rows = []
        n = round(stop / dt)
        for i in range(n + 1):
            t = i * dt
            rows.append([t, *fmu.getReal([vr[o] for o in outputs])])
            if i < n:
                fmu.doStep(currentCommunicationPoint=t, communicationStepSize=dt)
        fmu.terminate()
        fmu.freeInstance()
        return np.array(rows)
    finally:
        shutil.rmtree(folder, ignore_errors=True)


def write_resources(folder, files):
    res = pathlib.Path(folder) / "resources"
    res.mkdir(exist_ok=True)
    for name, text in files.items():
        (res / name).write_text(text)


WHEEL_OUTPUTS = ["q", "v", "a"]


def test_dll_exports_the_34_functions_and_needs_only_windows_dlls(wheel):
    folder, _md = wheel
    pe = PE((pathlib.Path(folder) / "binaries" / "win64" / "Wheel.dll").read_bytes())
    assert sorted(pe.exports()) == FMI2_CS_FUNCTIONS
    imports = [d.lower() for d in pe.imported_dlls()]
    # No mingw runtime (libgcc_s_seh-1.dll, libwinpthread-1.dll, ...): a Windows machine
    # without mingw must load it.
    assert not [d for d in imports if d.startswith("lib")], imports
    system = {"kernel32.dll", "ntdll.dll", "msvcrt.dll", "ucrtbase.dll", "userenv.dll",
              "ws2_32.dll", "advapi32.dll", "bcrypt.dll", "bcryptprimitives.dll"}
    assert all(d in system or d.startswith("api-ms-win-") for d in imports), imports


@pytest.mark.parametrize("sets", [{}, {"K": 125.0, "C": 15.0}, {"K": 90.0, "C": 24.0, "h": 2e-4}])
def test_wheel_dll_under_wine_matches_the_closed_form(wheel, wine, sets):
    rows = run_under_wine(wine, wheel, sets, WHEEL_OUTPUTS, stop=5.0, dt=0.01)
    params = {"m": 10.0, "K": 100.0, "C": 20.0, "q0": 0.1, **sets}
    t = rows[:, 0]
    q, v = closed_form(t, params["m"], params["K"], params["C"], params["q0"])
    err_q = np.max(np.abs(rows[:, 1] - q))
    err_v = np.max(np.abs(rows[:, 2] - v))
    assert err_q < 1e-12, err_q
    assert err_v < 1e-12, err_v
    # q'' satisfies the equation of motion at every point.
    resid = params["m"] * rows[:, 3] + params["C"] * rows[:, 2] + params["K"] * rows[:, 1]
    assert np.max(np.abs(resid)) < 1e-12


def test_wheel_dll_under_wine_equals_the_linux_binary_bit_for_bit(wheel, wine):
    sets = {"K": 110.0, "C": 18.0}
    win = run_under_wine(wine, wheel, sets, WHEEL_OUTPUTS, stop=2.0, dt=0.01)
    linux = run_linux_so("Wheel", sets, WHEEL_OUTPUTS, stop=2.0, dt=0.01)
    assert win.shape == linux.shape
    assert np.array_equal(win, linux), np.max(np.abs(win - linux))


@pytest.mark.parametrize("name, stop", [("Bogie", 1.0), ("VehicleTrack", 0.2), ("Vehicle", 1.0)])
def test_other_models_dll_under_wine_follow_the_linux_binary(wine, name, stop):
    fmu = extracted(name)
    try:
        md = fmu[1]
        outputs = [v.variable.name for v in md.outputs
                   if v.variable.type == "Real"]
        dt = float(md.defaultExperiment.stepSize)
        win = run_under_wine(wine, fmu, {}, outputs, stop=stop, dt=dt)
        linux = run_linux_so(name, {}, outputs, stop=stop, dt=dt)
    finally:
        shutil.rmtree(fmu[0], ignore_errors=True)
    scale = np.maximum(np.max(np.abs(linux), axis=0), 1e-300)
    rel = np.max(np.abs(win - linux) / scale)
    print(f"{name}: {len(outputs)} outputs, {len(win)} points, largest difference "
          f"{rel:.3g} of each output's range")
    assert rel < 1e-12, rel


def test_relative_profile_file_resolves_in_the_resources_folder_under_wine(wine):
    """VehicleTrack with a measured profile (irregularity = 10) named relative to the resources
    folder: the DLL gets that folder as file:///Z:/... and must open Z:/.../track.csv."""
    x = np.arange(0.0, 3001.0)
    z = 2e-3 * np.sin(2 * np.pi * x / 25.0)
    profile = {"track.csv": "x,z\n" + "".join(f"{float(a)!r},{float(b)!r}\n" for a, b in zip(x, z))}
    sets = {"irregularity": 10, "profile_file": "track.csv"}
    outputs = ["Z0_1"]
    fmu = extracted("VehicleTrack")
    try:
        write_resources(fmu[0], profile)
        win = run_under_wine(wine, fmu, sets, outputs, stop=0.2, dt=0.002)
    finally:
        shutil.rmtree(fmu[0], ignore_errors=True)
    linux = run_linux_so("VehicleTrack", sets, outputs, stop=0.2, dt=0.002, resources=profile)
    # The profile is what the wheels run on: within its range, and not flat.
    assert np.all(np.abs(win[:, 1:]) <= 2e-3 + 1e-12)
    assert np.ptp(win[:, 1]) > 1e-3, np.ptp(win[:, 1])
    assert np.max(np.abs(win - linux)) <= 1e-12 * 2e-3, np.max(np.abs(win - linux))


def test_wrong_state_calls_return_fmi2error_under_wine(wheel, wine):
    folder, md = wheel
    out = wine.importer(folder, md, "wrong-state", refs(md)["m"])
    result = dict(line.split(" ", 1) for line in out.splitlines())
    assert result["exports-missing"] == "0"
    assert result["instantiate-wrong-guid"] == "null"
    assert int(result["do-step-before-initialization"]) == FMI2_ERROR
    assert int(result["errors-logged"]) >= 1, "the error did not reach the importer's logger"
    assert int(result["set-fixed-after-initialization"]) == FMI2_ERROR
