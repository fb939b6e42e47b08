"""The FMUs shipped inside the package (``railuq/fmus/*.fmu``, the project's ``make fmu``
output at the time the wheel was built)."""
from __future__ import annotations

from pathlib import Path

from ._errors import FmuError

#: The folder of the shipped FMUs.
FMU_DIR: Path = Path(__file__).resolve().parent / "fmus"


def fmus() -> list[str]:
    """The names of the shipped FMUs (``["Bogie", "Vehicle", "VehicleTrack", "Wheel"]``)."""
    return sorted(p.stem for p in FMU_DIR.glob("*.fmu"))


def fmu_path(name: str) -> str:
    """The path of the shipped FMU ``name`` (``"Wheel"`` or ``"Wheel.fmu"``), for
    :func:`railuq.simulate`, a study's ``fmu`` key, or any FMI importer (fmpy, ...).

    Raises :class:`railuq.FmuError` naming the shipped FMUs when there is none of that name.
    """
    stem = name[: -len(".fmu")] if name.endswith(".fmu") else name
    path = FMU_DIR / f"{stem}.fmu"
    if not path.is_file():
        have = ", ".join(fmus()) or "none (the package was built without its FMUs)"
        raise FmuError(f"no FMU '{name}' in the package (it ships: {have})")
    return str(path)
