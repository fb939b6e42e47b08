"""numpy, imported when the package first needs it: the command line (``python -m railuq``, the
``railuq`` command and the worker processes of ``run --isolate``) and a study's runs never do,
so they start without paying numpy's import (about 0.1 s)."""
from __future__ import annotations

import importlib


class _Module:
    def __init__(self, name: str) -> None:
        self._name = name

    def __getattr__(self, attr: str) -> object:
        return getattr(importlib.import_module(self._name), attr)

    def __repr__(self) -> str:
        return f"<{self._name}, imported on first use>"


numpy = _Module("numpy")
