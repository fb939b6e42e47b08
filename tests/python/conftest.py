"""Shared fixtures for the fmpy cross-checks. The FMUs must have been built (`make fmu`):
a missing FMU is a failure, not a skip."""
import importlib.util
import os
import pathlib

import pytest

ROOT = pathlib.Path(__file__).resolve().parents[2]
FMU_DIR = pathlib.Path(os.environ.get("RAILUQ_FMU_DIR", ROOT / "target" / "fmu"))
DRIVER = pathlib.Path(os.environ.get("RAILUQ_DRIVER", ROOT / "target" / "release" / "uq-driver"))
TEST_FMU_DIR = pathlib.Path(os.environ.get("RAILUQ_TEST_FMU_DIR", ROOT / "target" / "test-fmu"))


def build_test_fmus() -> dict:
    """Builds the C test FMUs of uq-driver/tests/fmus (its build.py) into TEST_FMU_DIR; returns
    what build.build returns. A build that fails is a test failure."""
    script = ROOT / "uq-driver" / "tests" / "fmus" / "build.py"
    spec = importlib.util.spec_from_file_location("build_test_fmus", script)
    build = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(build)
    try:
        return build.build(TEST_FMU_DIR)
    except build.BuildError as e:
        pytest.fail(f"the C test FMUs cannot be built: {e}")


def fmu_path(name: str) -> str:
    path = FMU_DIR / f"{name}.fmu"
    if not path.is_file():
        pytest.fail(f"{path} is missing: run `make fmu` first")
    return str(path)


@pytest.fixture(scope="session")
def wheel_fmu() -> str:
    return fmu_path("Wheel")
