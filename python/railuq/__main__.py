"""``python -m railuq ARGS...``: the ``uq-driver`` command line (``run``, ``list``,
``simulate``, ``surrogate``, ``inspect``, ...; ``python -m railuq --help``). It finds the FMUs
shipped in the package, as ``railuq.builtin`` does."""
import sys

import railuq  # noqa: F401  (registers the shipped FMUs with the library)
from railuq import _railuq


def main() -> int:
    return _railuq.cli_main(["python -m railuq", *sys.argv[1:]])


if __name__ == "__main__":
    sys.exit(main())
