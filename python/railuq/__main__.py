"""``python -m railuq ARGS...`` (or the ``railuq`` command the package installs): the
``uq-driver`` command line (``run``, ``list``, ``simulate``, ``surrogate``, ``inspect``, ...;
``python -m railuq --help``). It finds the FMUs shipped in the package, as ``railuq.builtin``
does.

Commands that start other processes of the command line (``run --isolate`` starts worker
processes, ``slurm`` writes batch scripts that run shards) start the ``railuq`` command
installed beside this interpreter (``$UQ_DRIVER_EXE`` overrides it), since the program running
here is the Python interpreter, not ``uq-driver``."""
import os
import shutil
import sys
import sysconfig
from pathlib import Path
from typing import Optional

import railuq  # noqa: F401  (registers the shipped FMUs with the library)
from railuq import _railuq


def _installed_command() -> Optional[str]:
    """The ``railuq`` console command of this installation (pip writes it into the scripts
    folder of the environment the package is installed in), or one on PATH."""
    scripts = sysconfig.get_path("scripts")
    if scripts:
        here = Path(scripts) / ("railuq.exe" if os.name == "nt" else "railuq")
        if here.is_file() and os.access(here, os.X_OK):
            return str(here)
    return shutil.which("railuq")


def main() -> int:
    if "UQ_DRIVER_EXE" not in os.environ:
        command = _installed_command()
        if command is not None:
            os.environ["UQ_DRIVER_EXE"] = command
    return _railuq.cli_main(["python -m railuq", *sys.argv[1:]])


if __name__ == "__main__":
    sys.exit(main())
