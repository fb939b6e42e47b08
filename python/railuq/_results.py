"""The results of a study: statistics over time per output, scalar quantities, Sobol'
indices, exceedance probabilities, ``summary.json``, and the chaos surrogate."""
from __future__ import annotations

import json
from functools import cached_property
from pathlib import Path

from . import _railuq

# typing, logging, tempfile and difflib are imported where they are used: `import railuq`
# stays cheap (the Python path's cost over the command line is measured in `make bench`).
TYPE_CHECKING = False
if TYPE_CHECKING:
    import tempfile
    from typing import Any, Optional, Union

    import numpy as np

    Array = np.ndarray
else:
    from ._lazy import numpy as np


def _f64(values: Any) -> Array:
    return np.asarray(values, dtype=np.float64)


class Results:
    """What a finished study returns (:meth:`railuq.Study.run`): the library's numbers, the
    same bits as the command line writes to ``<out>/<output>.csv`` and ``summary.json``.

    A name given to :meth:`mean`, :meth:`std`, :meth:`quantiles` and :meth:`sobol` is an
    output variable (the result is over :attr:`time`: float64 arrays) or a scalar quantity
    of interest (``[[qoi]]``: floats). An unknown name raises KeyError listing the names.

    ``out`` is the study's folder. When the study ran into a temporary folder, it lives as
    long as this object: :meth:`close` (or leaving a ``with`` block, or garbage collection)
    deletes it.
    """

    def __init__(self, raw: dict, out: Path, study: str,
                 tmp: Optional[tempfile.TemporaryDirectory] = None) -> None:
        self._outputs = {o["name"]: o for o in raw["outputs"]}
        self._quantities = {q["name"]: q for q in json.loads(raw["quantities_json"])}
        self._tmp = tmp
        #: The random parameters' names, in study order (the order of Sobol' indices).
        self.parameters: list[str] = list(raw["parameters"])
        #: Warnings of the study (also in ``summary["warnings"]``) not shown while it ran.
        self.warnings: list[str] = list(raw["warnings"])
        #: The study's name.
        self.study: str = study
        #: The study's output folder.
        self.out: Path = Path(out)

    # ------------------------------------------------------------------ names

    @property
    def outputs(self) -> list[str]:
        """The output variables, analysed over time."""
        return list(self._outputs)

    @property
    def quantities(self) -> list[str]:
        """The scalar quantities of interest."""
        return list(self._quantities)

    def _output(self, name: str) -> Optional[dict]:
        return self._outputs.get(name)

    def _lookup(self, name: str) -> tuple[Optional[dict], Optional[dict]]:
        o, q = self._outputs.get(name), self._quantities.get(name)
        if o is None and q is None:
            raise KeyError(f"'{name}' is neither an output nor a quantity of {self.study} "
                           f"(outputs: {', '.join(self.outputs) or 'none'}; quantities: "
                           f"{', '.join(self.quantities) or 'none'})")
        return o, q

    # ------------------------------------------------------------------ statistics

    @property
    def time(self) -> Array:
        """The communication points (s) of the outputs."""
        first = next(iter(self._outputs.values()), None)
        return _f64([] if first is None else first["times"])

    def mean(self, var: str) -> Union[Array, float]:
        """The mean of output ``var`` over :attr:`time`, or of quantity ``var``."""
        o, q = self._lookup(var)
        return _f64(o["mean"]) if o is not None else _num(q["mean"])

    def std(self, var: str) -> Union[Array, float]:
        """The standard deviation of output ``var`` over :attr:`time`, or of quantity
        ``var``."""
        o, q = self._lookup(var)
        return _f64(o["std"]) if o is not None else _num(q["std"])

    def quantiles(self, var: str) -> dict[float, Union[Array, float]]:
        """``{level: values}``: the quantiles of output ``var`` over :attr:`time` (arrays),
        or of quantity ``var`` (floats), at the levels of the study's ``[analysis]``."""
        o, q = self._lookup(var)
        if o is not None:
            return {float(level): _f64(v) for level, v in o["quantiles"]}
        return {float(level): _num(v) for level, v in q["quantiles"]}

    def sobol(self, name: str) -> Optional[dict[str, Any]]:
        """The Sobol' indices of ``name``, labelled by parameter, where the method gives
        them (None otherwise):

        - a quantity: ``{"first": {param: float}, "total": {param: float}}`` (with
          ``"first_ci"``, ``"total_ci"`` (``[low, high]``) and ``"ci_level"`` where the
          method estimates intervals), as in ``summary.json``;
        - an output: ``{"first": {param: array over time}, "total": {...}}`` (with
          ``"first_ci"``/``"total_ci"`` as ``{param: array (times, 2)}`` and ``"ci_level"``
          where estimated).
        """
        o, q = self._lookup(name)
        if o is None:
            return q.get("sobol")
        s = o["sobol"]
        if s is None:
            return None

        def by_param(rows: list) -> dict[str, Array]:
            a = _f64(rows).reshape(len(rows), len(self.parameters))
            return {p: a[:, i].copy() for i, p in enumerate(self.parameters)}

        out: dict[str, Any] = {"first": by_param(s["first"]), "total": by_param(s["total"])}
        if "level" in s:
            for key in ("first_ci", "total_ci"):
                rows = s[key]
                a = _f64(rows).reshape(len(rows), len(self.parameters), 2)
                out[key] = {p: a[:, i, :].copy() for i, p in enumerate(self.parameters)}
            out["ci_level"] = float(s["level"])
        return out

    @property
    def exceedance(self) -> dict[str, list[dict[str, float]]]:
        """``{quantity: [{"limit", "p", "std_error"}, ...]}``: P(quantity > limit) for the
        limits of each quantity that has ``exceed`` limits (standard error of p as the
        summary gives it)."""
        return {
            name: [{"limit": _num(l), "p": _num(p), "std_error": _num(se)}
                   for l, p, se in q["exceedance"]]
            for name, q in self._quantities.items() if q.get("exceedance")
        }

    def quantity(self, name: str) -> dict[str, Any]:
        """Everything ``summary.json`` says of quantity ``name`` (mean, std, quantiles,
        exceedance with counts, Sobol', definition, unit, ...)."""
        _, q = self._lookup(name)
        if q is None:
            raise KeyError(f"'{name}' is an output, not a quantity")
        return q

    @cached_property
    def summary(self) -> dict[str, Any]:
        """``summary.json`` of the study, as a dict."""
        return json.loads((self.out / "summary.json").read_text(encoding="utf-8"))

    # ------------------------------------------------------------------ tables

    def _columns(self) -> dict[tuple[str, str], Array]:
        cols: dict[tuple[str, str], Array] = {}
        for name, o in self._outputs.items():
            for stat in ("mean", "std", "lower_3sigma", "upper_3sigma"):
                cols[(name, stat)] = _f64(o[stat])
            for level, v in o["quantiles"]:
                cols[(name, f"q{level:g}")] = _f64(v)
            if o["std_error_mean"] is not None:
                cols[(name, "std_error_mean")] = _f64(o["std_error_mean"])
        return cols

    def to_pandas(self) -> Any:
        """The statistics over time as a pandas DataFrame: index ``time`` (s), columns
        ``(output, statistic)`` with statistic ``mean``, ``std``, ``lower_3sigma``,
        ``upper_3sigma``, ``q<level>`` for each quantile, and ``std_error_mean`` for sampling
        methods. Needs pandas."""
        import pandas as pd

        cols = self._columns()
        df = pd.DataFrame(cols, index=pd.Index(self.time, name="time"))
        df.columns = pd.MultiIndex.from_tuples(list(cols), names=["output", "statistic"])
        return df

    def to_xarray(self) -> Any:
        """The statistics over time as an xarray Dataset: one variable per
        ``<output>_<statistic>`` of :meth:`to_pandas`, over dimension ``time``, with the
        output's unit in ``attrs``; the scalar quantities' mean and std as 0-d variables.
        Needs xarray (``pip install xarray``)."""
        import xarray as xr

        data: dict[str, Any] = {}
        for (name, stat), v in self._columns().items():
            unit = self._outputs[name]["unit"]
            data[f"{name}_{stat}"] = xr.DataArray(
                v, dims=("time",), attrs={"unit": unit} if unit else {})
        for name, q in self._quantities.items():
            attrs = {"unit": q["unit"]} if q.get("unit") else {}
            data[f"{name}_mean"] = xr.DataArray(_num(q["mean"]), attrs=attrs)
            data[f"{name}_std"] = xr.DataArray(_num(q["std"]), attrs=attrs)
        return xr.Dataset(data, coords={"time": self.time}, attrs={"study": self.study})

    # ------------------------------------------------------------------ surrogate

    def surrogate(self, var: str) -> "Surrogate":
        """The chaos surrogate of output or quantity ``var`` (``surrogate.json``, written by
        the chaos methods: SCM, sparse grids, PCE regression). Raises
        :class:`railuq.SurrogateError` when the method wrote none."""
        return Surrogate(_railuq.Surrogate.load(str(self.out)), var)

    # ------------------------------------------------------------------ lifetime

    def close(self) -> None:
        """Deletes the temporary folder the study ran into (nothing for a folder given as
        ``out``). The numbers already read stay usable; :attr:`summary` and
        :meth:`surrogate` need the folder."""
        if self._tmp is not None:
            self._tmp.cleanup()
            self._tmp = None

    def __enter__(self) -> "Results":
        return self

    def __exit__(self, *exc: object) -> None:
        self.close()

    def __repr__(self) -> str:
        return (f"<railuq.Results {self.study}: outputs {self.outputs}, quantities "
                f"{self.quantities}, in {self.out}>")


class SuiteResults:
    """What a suite (a study with ``[[variants]]``) returns: each variant's :class:`Results`
    in ``variants`` (by name, in file order), the comparison in ``out``."""

    def __init__(self, variants: dict[str, Results], out: Path, study: str,
                 tmp: Optional[tempfile.TemporaryDirectory] = None) -> None:
        #: Each variant's results.
        self.variants: dict[str, Results] = variants
        #: The suite's output folder.
        self.out: Path = Path(out)
        #: The suite's name.
        self.study: str = study
        self._tmp = tmp

    def __getitem__(self, variant: str) -> Results:
        return self.variants[variant]

    @cached_property
    def summary(self) -> dict[str, Any]:
        """The suite's ``summary.json``, as a dict."""
        return json.loads((self.out / "summary.json").read_text(encoding="utf-8"))

    def close(self) -> None:
        """Deletes the temporary folder the suite ran into (if any)."""
        if self._tmp is not None:
            self._tmp.cleanup()
            self._tmp = None

    def __enter__(self) -> "SuiteResults":
        return self

    def __exit__(self, *exc: object) -> None:
        self.close()


def _num(v: Any) -> float:
    """A number of summary.json (null, for a NaN, as nan)."""
    return float("nan") if v is None else float(v)


class Surrogate:
    """The chaos surrogate of one output or quantity of a study: a polynomial in the random
    parameters that stands in for the model (the ``surrogate.json`` that ``uq-driver
    surrogate eval|sample`` read, the same numbers).

    Call it at points of the parameters (:attr:`inputs`, in study order):

    - ``s(x)`` with ``x`` of shape ``(d,)`` or ``(n, d)`` (float64; d = ``len(inputs)``);
    - ``s({"K": 95.0})`` or ``s({"K": array, "C": array})``: by name, the others at their
      nominal value (the mean).

    It returns, for an output, an array over :attr:`times` (shape ``(m,)``, or ``(n, m)``
    for n points); for a quantity a float (or shape ``(n,)``).
    """

    def __init__(self, inner: Any, var: str) -> None:
        self._s = inner
        columns = inner.columns
        names = [c[0] for c in columns]
        if var not in names:
            raise KeyError(f"the surrogate has no '{var}' (it has: {', '.join(names)})")
        self._which = names.index(var)
        times = columns[self._which][1]
        #: The output or quantity.
        self.name: str = var
        #: The inputs (the random parameters), in the order of a point's values.
        self.inputs: list[str] = list(inner.inputs)
        #: The times (s) of an output's values; None for a quantity.
        self.times: Optional[Array] = None if times is None else _f64(times)

    def _shape(self, n: int) -> tuple[int, ...]:
        return (n,) if self.times is None else (n, len(self.times))

    def _points(self, x: Any) -> tuple[Array, bool]:
        d = len(self.inputs)
        if isinstance(x, dict):
            unknown = [k for k in x if k not in self.inputs]
            if unknown:
                # The library's message (and exception) for an unknown input.
                self._s.point([(str(unknown[0]), 0.0)])
            arrays = {k: np.asarray(v, dtype=np.float64) for k, v in x.items()}
            single = all(a.ndim == 0 for a in arrays.values())
            if single:
                return _f64(self._s.point([(k, float(a)) for k, a in arrays.items()])), True
            n = max(a.size for a in arrays.values())
            pts = np.tile(_f64(self._s.point([])), (n, 1))
            for k, a in arrays.items():
                pts[:, self.inputs.index(k)] = np.broadcast_to(a.reshape(-1), (n,))
            return pts, False
        a = np.ascontiguousarray(x, dtype=np.float64)
        if a.ndim == 1 and a.shape[0] == d:
            return a.reshape(1, d), True
        if a.ndim == 2 and a.shape[1] == d:
            return a, False
        raise ValueError(f"points of {d} inputs ({', '.join(self.inputs)}): give shape "
                         f"({d},) or (n, {d}), not {a.shape}")

    def __call__(self, x: Any) -> Union[Array, float]:
        pts, single = self._points(x)
        pts = np.ascontiguousarray(pts.reshape(-1, len(self.inputs)))
        n = pts.shape[0]
        y = np.frombuffer(self._s.eval(pts.tobytes(), n, self._which), dtype=np.float64).copy()
        y = y.reshape(self._shape(n))
        if single:
            return float(y[0]) if self.times is None else y[0]
        return y

    def sample(self, n: int, seed: int = 0) -> tuple[Array, Array]:
        """``n`` random points of the parameters' joint law (point i from the stream
        ``(seed, i)``: the points of ``uq-driver surrogate sample -n N --seed S``) and the
        surrogate there: ``(x, y)`` with x of shape ``(n, d)`` and y of shape ``(n, m)`` for
        an output (``(n,)`` for a quantity)."""
        xb, yb = self._s.sample(int(n), int(seed), self._which)
        x = np.frombuffer(xb, dtype=np.float64).reshape(int(n), len(self.inputs))
        y = np.frombuffer(yb, dtype=np.float64).reshape(self._shape(int(n)))
        return x.copy(), y.copy()

    def __repr__(self) -> str:
        what = "quantity" if self.times is None else f"output over {len(self.times)} times"
        return f"<railuq.Surrogate {self.name} ({what}) of {', '.join(self.inputs)}>"
