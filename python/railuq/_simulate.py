"""One simulation of an FMU, as ``uq-driver simulate``."""
from __future__ import annotations

import os
from collections.abc import Iterable, Mapping

from . import _railuq
from ._progress import forward_messages

# typing, logging, tempfile and difflib are imported where they are used: `import railuq`
# stays cheap (the Python path's cost over the command line is measured in `make bench`).
TYPE_CHECKING = False
if TYPE_CHECKING:
    from typing import Any, Union

    import numpy as np

    PathLike = Union[str, os.PathLike[str]]
else:
    from ._lazy import numpy as np


class Columns(dict):  # type: ignore[type-arg]
    """The series of :func:`simulate` without pandas: a dict of float64 numpy arrays by
    variable name (``"time"`` first), with an ``attrs`` dict as a pandas DataFrame has
    (``attrs["calculated_strings"]``)."""

    attrs: dict[str, Any]


def simulate(
    fmu: PathLike,
    set: Mapping[str, bool | float | int | str] | None = None,
    stop: float | None = None,
    step: float | None = None,
    outputs: Iterable[str] | None = None,
    start: float | None = None,
) -> Any:
    """Runs ``fmu`` once, as ``uq-driver simulate`` does, and returns the series.

    ``set``: values set before initialization, by variable name (a bool, a number, or a text
    for a String or Enumeration variable). ``start``, ``stop``, ``step`` (s): the time grid
    (each ``None`` takes the FMU's default experiment; ``start`` else 0). ``outputs``: the
    variables to record (``None``: every output that can be recorded).

    Returns a pandas DataFrame with a ``time`` column and one column per variable when pandas
    is installed, else a dict of float64 numpy arrays (``"time"`` first). Where the FMU ends
    the simulation early, the series end there (as in fmpy), with a note logged. The FMU's
    String calculated parameters, read after the run (e.g. ``solver.kernel``, the instruction
    sets VehicleTrack's equations ran on: record it with a result), are
    ``attrs["calculated_strings"]``, a dict by name (empty when the FMU has none), of the
    DataFrame or, without pandas, of the dict.

    Raises :class:`railuq.FmuError` (the FMU cannot be opened), :class:`railuq.StudyError` (an
    unknown variable, a bad value or time grid) or :class:`railuq.RunError` (the run failed),
    with the command line's messages.
    """
    pairs = [(str(k), v) for k, v in (set or {}).items()]
    try:
        names, times, series, strings = _railuq.simulate(
            os.fspath(fmu), pairs, [str(o) for o in (outputs or [])], start, stop, step
        )
    finally:
        forward_messages(None)
    columns = Columns(time=np.asarray(times, dtype=np.float64))
    for name, values in zip(names, series):
        columns[name] = np.asarray(values, dtype=np.float64)
    try:
        import pandas as pd
    except ImportError:
        columns.attrs = {"calculated_strings": dict(strings)}
        return columns
    df = pd.DataFrame(columns)
    df.attrs["calculated_strings"] = dict(strings)
    return df
