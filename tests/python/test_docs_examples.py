"""Every study file of the user guide (docs/src/examples/*.toml, included into its pages) runs.

Long studies run in a quick mode: the same file with fewer runs or shorter runs (the values of a
few keys replaced, every key kept). Where a page quotes results of a cheap study, the study runs
in full and the quoted numbers are checked, so the guide cannot drift from the program."""
import json
import os
import pathlib
import re
import shutil
import subprocess
import sys

import pytest

from conftest import DRIVER, FMU_DIR, ROOT, fmu_path

EXAMPLES = ROOT / "docs" / "src" / "examples"
BUILD_SCRIPT = ROOT / "uq-driver" / "tests" / "fmus" / "build.py"
TEST_FMU_DIR = ROOT / "target" / "test-fmu"

# Quick mode: text replaced in the study file (each must occur, so a renamed key fails here).
QUICK = {
    "first-study.toml": {"samples = 1000": "samples = 50"},
    "wheel-lhs.toml": {"samples = 1000": "samples = 50", "replicates = 8": "replicates = 2"},
    "bogie-ramp.toml": {"nodes = 3": "nodes = 2"},
    "bogie-constant-speed.toml": {"duration = 300.0": "duration = 20.0",
                                  "tolerance = 0.02": "tolerance = 5.0"},
    "ride-comfort-nested.toml": {"samples = 16": "samples = 2", "stop = 6.0": "stop = 3.0",
                                 "segment = 5.0": "segment = 2.0"},
}
FULL = ["wheel-scm.toml", "own-fmu-ishigami.toml", "borehole-pce.toml", "borehole-qmc.toml"]


def functions_fmu() -> pathlib.Path:
    fmu = TEST_FMU_DIR / "Functions.fmu"
    if not fmu.is_file():
        r = subprocess.run([sys.executable, str(BUILD_SCRIPT), str(TEST_FMU_DIR)],
                           capture_output=True, text=True)
        assert r.returncode == 0, f"building the test FMUs failed:\n{r.stdout}\n{r.stderr}"
    return fmu


def run_example(name: str, tmp: pathlib.Path, quick: bool) -> dict:
    tmp.mkdir(parents=True, exist_ok=True)
    text = (EXAMPLES / name).read_text(encoding="utf-8")
    if quick:
        for old, new in QUICK[name].items():
            assert old in text, f"{name}: the quick mode replaces '{old}', which is gone"
            text = text.replace(old, new)
    study = tmp / name
    study.write_text(text)
    fmu = re.search(r'^fmu = "([^"]+)"', text, re.M).group(1)
    if fmu == "Functions.fmu":
        shutil.copy(functions_fmu(), tmp / fmu)  # beside the study file, as the page says
    else:
        fmu_path(fmu.removesuffix(".fmu"))  # fails with a clear message when missing
    out = tmp / "out"
    r = subprocess.run([str(DRIVER), "run", str(study), "--out", str(out), "--no-report"],
                       capture_output=True, text=True, timeout=300,
                       env={**os.environ, "RAILUQ_FMU_DIR": str(FMU_DIR)})
    assert r.returncode == 0, f"{name}:\n{r.stderr}"
    return json.loads((out / "summary.json").read_text())


def test_every_example_is_run_here():
    files = {p.name for p in EXAMPLES.glob("*.toml")}
    assert files == set(QUICK) | set(FULL), "every example must be in QUICK or FULL"


def test_every_example_is_shown_in_the_guide():
    pages = "".join(p.read_text(encoding="utf-8") for p in (ROOT / "docs" / "src").rglob("*.md"))
    for p in EXAMPLES.glob("*.toml"):
        assert f"examples/{p.name}" in pages, f"{p.name} is included in no page"


def test_the_readme_first_study_is_the_guide_s():
    readme = (ROOT / "README.md").read_text(encoding="utf-8")
    block = re.search(r"```toml\n(.*?)```", readme, re.S).group(1)
    assert block == (EXAMPLES / "first-study.toml").read_text(encoding="utf-8")


@pytest.mark.parametrize("name", sorted(QUICK))
def test_example_runs_in_quick_mode(name, tmp_path):
    s = run_example(name, tmp_path, quick=True)
    assert s["model_runs"] > 0


def test_wheel_tutorial_numbers(tmp_path):
    q = run_example("wheel-scm.toml", tmp_path, quick=False)["quantities"]["q_max_late"]
    assert round(q["mean"], 4) == 0.0351 and round(q["std"], 5) == 0.00453
    assert round(q["sobol"]["first"]["C"], 2) == 0.81
    assert round(q["sobol"]["first"]["K"], 2) == 0.19


def test_own_fmu_tutorial_matches_the_ishigami_closed_form(tmp_path):
    import math
    a, b = 7.0, 0.1
    mean = a / 2
    var = a * a / 8 + b * math.pi ** 4 / 5 + b * b * math.pi ** 8 / 18 + 0.5
    q = run_example("own-fmu-ishigami.toml", tmp_path, quick=False)["quantities"]["y"]
    assert abs(q["mean"] - mean) < 4 * q["std_error_mean"]
    assert abs(q["std"] - math.sqrt(var)) < 0.01 * math.sqrt(var)
    assert round(q["std"], 2) == 3.72 and round(math.sqrt(var), 4) == 3.7208


def test_high_dimensional_tutorial_chaos_agrees_with_the_reference(tmp_path):
    pce = run_example("borehole-pce.toml", tmp_path / "pce", quick=False)["quantities"]["flow"]
    ref = run_example("borehole-qmc.toml", tmp_path / "qmc", quick=False)["quantities"]["flow"]
    assert abs(pce["mean"] / ref["mean"] - 1) < 1e-3
    assert abs(pce["std"] / ref["std"] - 1) < 1e-2
    assert round(pce["sobol"]["first"]["rw"], 2) == 0.66
    assert pce["chaos_error"]["value"] < 0.05


def test_slurm_tutorial_shards_merge_to_the_single_machine_result(tmp_path):
    """The tutorial's plan / run-shard / merge on the wheel study (quick mode) gives the same
    q.csv, byte for byte, as one run."""
    text = (EXAMPLES / "wheel-lhs.toml").read_text(encoding="utf-8")
    for old, new in QUICK["wheel-lhs.toml"].items():
        text = text.replace(old, new)
    study = tmp_path / "wheel-lhs.toml"
    study.write_text(text)
    fmu_path("Wheel")
    env = {**os.environ, "RAILUQ_FMU_DIR": str(FMU_DIR)}

    def drive(*args):
        r = subprocess.run([str(DRIVER), *args], capture_output=True, text=True, timeout=120,
                           env=env)
        assert r.returncode == 0, f"{args}:\n{r.stderr}"

    plan = tmp_path / "plan"
    drive("plan", str(study), "--shards", "4", "--out", str(plan))
    for k in range(4):
        drive("run-shard", str(plan), "--shard", str(k))
    drive("merge", str(plan), "--no-report")
    drive("run", str(study), "--out", str(tmp_path / "one"), "--no-report")
    assert (plan / "result" / "q.csv").read_bytes() == (tmp_path / "one" / "q.csv").read_bytes()
