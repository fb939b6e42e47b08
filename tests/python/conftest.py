"""Shared fixtures for the fmpy cross-checks. The FMUs must have been built (`make fmu`):
a missing FMU is a failure, not a skip."""
import os
import pathlib

import pytest

ROOT = pathlib.Path(__file__).resolve().parents[2]
FMU_DIR = pathlib.Path(os.environ.get("RAILUQ_FMU_DIR", ROOT / "target" / "fmu"))
DRIVER = pathlib.Path(os.environ.get("RAILUQ_DRIVER", ROOT / "target" / "release" / "uq-driver"))


def fmu_path(name: str) -> str:
    path = FMU_DIR / f"{name}.fmu"
    if not path.is_file():
        pytest.fail(f"{path} is missing: run `make fmu` first")
    return str(path)


@pytest.fixture(scope="session")
def wheel_fmu() -> str:
    return fmu_path("Wheel")
