"""Studies: from a TOML file, TOML text, a dict of the same schema, or a built-in; and their
runs."""
from __future__ import annotations

import os
from collections.abc import Mapping
from pathlib import Path

from . import _railuq
from ._errors import StudyError
from ._progress import Display, forward_messages
from ._results import Results, SuiteResults

# typing, logging, tempfile and difflib are imported where they are used: `import railuq`
# stays cheap (the Python path's cost over the command line is measured in `make bench`).
TYPE_CHECKING = False
if TYPE_CHECKING:
    from typing import Any, Optional, Union

    PathLike = Union[str, os.PathLike[str]]


def builtins() -> list[str]:
    """The names of the built-in studies (``uq-driver list``)."""
    return [name for name, _ in _railuq.builtins()]


def builtin(name: str) -> "Study":
    """The built-in study ``name`` (e.g. ``"wheel-scm"``; ``"builtin:wheel-scm"`` too).

    Raises :class:`railuq.StudyError` for an unknown name (with the closest one).
    """
    name = name[len("builtin:"):] if name.startswith("builtin:") else name
    names = builtins()
    if name not in names:
        import difflib

        close = difflib.get_close_matches(name, names, n=1)
        hint = f"\nhint: did you mean '{close[0]}'?" if close else ""
        raise StudyError(f"no built-in study '{name}' (railuq.builtins() lists them){hint}")
    return Study(_railuq.Study.load(f"builtin:{name}"))


class Study:
    """A study, parsed and validated by the library: what ``uq-driver run`` takes.

    Make one with :meth:`from_file`, :meth:`from_toml`, :meth:`from_dict` or
    :func:`railuq.builtin`; run it with :meth:`run`. The schema (``name``, ``fmu``,
    ``[experiment]``, ``[[parameters]]``, ``[method]``, ``[outputs]``, ``[[qoi]]``, ...) is
    that of the study files, documented in the project's README.
    """

    def __init__(self, inner: Any) -> None:
        self._inner = inner

    @classmethod
    def from_file(cls, path: PathLike) -> "Study":
        """Reads a study file (TOML); a relative ``fmu`` is looked for beside it first."""
        return cls(_railuq.Study.load(os.fspath(path)))

    @classmethod
    def from_toml(cls, text: str, base: Optional[PathLike] = None,
                  origin: str = "toml") -> "Study":
        """A study from TOML text; relative paths start from ``base`` (default: the current
        folder, then the FMU search path). ``origin`` names the text in error messages."""
        return cls(_railuq.Study.parse(text, origin, None if base is None else os.fspath(base)))

    @classmethod
    def from_dict(cls, study: Mapping[str, Any], base: Optional[PathLike] = None,
                  origin: str = "dict") -> "Study":
        """A study from a dict of the TOML schema: tables are dicts, arrays of tables lists
        of dicts (``{"name": ..., "parameters": [{"name": "K", ...}], "method": {"kind":
        "scm", ...}}``); numpy numbers and arrays are accepted, a key set to None is left out.

        Raises :class:`railuq.StudyError` naming the offending key (line:column refer to the
        dict written as TOML, :attr:`toml` of a valid study), or TypeError for a value that
        has no TOML form.
        """
        return cls.from_toml(_railuq.toml_from_dict(study), base, origin)

    # ------------------------------------------------------------------ what it is

    @property
    def name(self) -> str:
        return self._inner.name

    @property
    def description(self) -> str:
        return self._inner.description

    @property
    def origin(self) -> str:
        """The file, ``builtin:NAME``, ``toml`` or ``dict``."""
        return self._inner.origin

    @property
    def toml(self) -> str:
        """The study as TOML text."""
        return self._inner.source

    @property
    def fmu(self) -> Optional[str]:
        """The FMU's path as resolved (None for a method that runs no FMU)."""
        p = self._inner.fmu
        return None if p is None else str(p)

    @property
    def parameters(self) -> list[str]:
        """The random parameters' names, in study order."""
        return self._inner.parameters

    @property
    def outputs(self) -> list[str]:
        """The output variables analysed over time."""
        return self._inner.outputs

    @property
    def quantities(self) -> list[str]:
        """The scalar quantities of interest (``[[qoi]]``)."""
        return self._inner.quantities

    @property
    def method(self) -> str:
        """The method, in words (``"SCM tensor grid, 6 nodes per parameter"``, ...)."""
        return self._inner.method

    @property
    def seed(self) -> int:
        return self._inner.seed

    @property
    def experiment(self) -> tuple[float, float, float]:
        """``(start, stop, step)`` in s."""
        return self._inner.experiment

    @property
    def variants(self) -> Optional[list[str]]:
        """The variants' names, for a suite (a study with ``[[variants]]``), else None."""
        return self._inner.variants

    def __repr__(self) -> str:
        return f"<railuq.Study {self.name} ({self.origin}): {self.method}>"

    # ------------------------------------------------------------------ running it

    def run(
        self,
        out: Optional[PathLike] = None,
        threads: Optional[int] = None,
        progress: bool = True,
        *,
        fresh: bool = False,
        allow_failures: bool = False,
        report: Optional[bool] = None,
        yes: bool = False,
    ) -> Union[Results, SuiteResults]:
        """Runs the study, as ``uq-driver run STUDY --out OUT``, and returns its results.

        ``out``: the output folder (the resumable results store, ``summary.json``, the CSV
        files, ``surrogate.json`` for a chaos method, the HTML report). A study run again
        into the same folder resumes: finished points are not run again. ``None``: a new
        temporary folder, deleted when the :class:`Results` are closed (``close()``, a
        ``with`` block) or garbage-collected; copy what you need out of ``results.out``
        before.

        ``threads``: worker threads (default: all cores). ``progress``: show a progress bar
        and the library's notes (see :mod:`railuq._progress`); False: quiet, the notes go to
        the ``railuq`` logger. ``fresh``: discard earlier results in ``out``.
        ``allow_failures``: Monte Carlo, LHS, QMC, pce_regression and sobol_sampling go on
        past failed points (collocation and sparse grids stop). ``report``: write
        the plots and ``index.html`` (default: when ``out`` is given). ``yes``: start a
        study above the size limits without asking.

        The runs release the GIL. Ctrl-C (KeyboardInterrupt; "interrupt the kernel" in
        Jupyter) stops the study as on the command line: no point starts after it, the
        points in flight finish and are stored, then KeyboardInterrupt is raised; running
        again into the same ``out`` resumes (a temporary folder is deleted, so give ``out``
        to resume).

        Raises :class:`railuq.StudyError`, :class:`railuq.FmuError`,
        :class:`railuq.RunError` or :class:`railuq.Incomplete`, with the command line's
        messages.
        """
        tmp = None
        if out is None:
            import tempfile

            tmp = tempfile.TemporaryDirectory(prefix=f"railuq-{self.name}-")
            out_dir = Path(tmp.name)
        else:
            out_dir = Path(os.fspath(out))
        if report is None:
            report = tmp is None
        display = Display(self.name) if progress else None
        try:
            raw = self._inner.run(
                str(out_dir), threads, fresh, allow_failures, report, yes,
                display.update if display is not None else _quiet,
            )
        except BaseException:
            if tmp is not None:
                tmp.cleanup()
            raise
        finally:
            forward_messages(display)
            if display is not None:
                display.close()
        if isinstance(raw, dict):
            result = Results(raw, out_dir, self.name, tmp)
            _warn(result.warnings, display)
            return result
        variants = {name: Results(r, out_dir / name, name, None) for name, r in raw}
        for r in variants.values():
            _warn(r.warnings, display)
        return SuiteResults(variants, out_dir, self.name, tmp)


def _quiet(_done: int, _total: int, messages: list[str]) -> None:
    forward_messages(None, messages)


def _warn(warnings: list[str], display: Optional[Display]) -> None:
    """The warnings of the results not printed while the study ran (as ``uq-driver run``
    prints them at the end)."""
    forward_messages(display, [f"uq-driver: warning: {w}" for w in warnings])
