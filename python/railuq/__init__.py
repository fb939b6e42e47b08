"""railuq: uncertainty quantification of FMI 2.0 Co-Simulation FMUs, from Python.

A thin layer over the uq-driver library (the Rust library behind the ``uq-driver`` command
line): the same studies (TOML files, dicts of the same schema, or the built-in studies), the
same runs, results and error messages, bit for bit. The railway FMUs of the project (Wheel,
Bogie, VehicleTrack, Vehicle) ship inside the package.

    >>> import railuq
    >>> r = railuq.builtin("wheel-scm").run()          # into a temporary folder
    >>> r.mean("q")[:3]                                  # numpy arrays over r.time
    >>> df = railuq.simulate(railuq.fmu_path("Wheel"), set={"K": 90.0}, stop=5, step=0.01)

``python -m railuq ARGS...`` is the ``uq-driver`` command line (``python -m railuq run
builtin:wheel-scm --out out``).
"""
from __future__ import annotations

from pathlib import Path

from . import _railuq
from ._errors import Error, FmuError, Incomplete, RunError, StudyError, SurrogateError
from ._fmus import FMU_DIR, fmu_path, fmus
from ._results import Results, SuiteResults, Surrogate
from ._simulate import simulate
from ._study import Study, builtin, builtins

__version__: str = _railuq.__version__

__all__ = [
    "Error",
    "FMU_DIR",
    "FmuError",
    "Incomplete",
    "Results",
    "RunError",
    "Study",
    "StudyError",
    "SuiteResults",
    "Surrogate",
    "SurrogateError",
    "builtin",
    "builtins",
    "fmu_path",
    "fmus",
    "simulate",
]

# The built-in studies (and any study naming `fmu = "Wheel.fmu"`) find the FMUs shipped in
# the package, after $RAILUQ_FMU_DIR.
if Path(FMU_DIR).is_dir():
    _railuq.add_fmu_dir(str(FMU_DIR))
