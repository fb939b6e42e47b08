"""The exceptions of railuq. Their message is the text the `uq-driver` command line prints for
the same error (with its `hint:` lines), so a message found in the CLI's documentation or an
issue reads the same here."""


class Error(Exception):
    """Base class of every error railuq raises (besides TypeError for a value of the wrong
    Python type, and KeyboardInterrupt after Ctrl-C)."""


class StudyError(Error, ValueError):
    """The study is not valid: a TOML or dict key or value (the message names the key, with a
    "did you mean" hint for a misspelt one), an unknown built-in, a variable the FMU does not
    have, a study too large to start without ``yes=True``."""


class FmuError(Error):
    """An FMU cannot be found (the message lists every place searched), opened or loaded."""


class RunError(Error, RuntimeError):
    """The study failed while running: failed points (the message names the first), the
    results store, the folder's lock, the analysis or the report."""


class Incomplete(RunError):
    """The study stopped before every point was run; run it again into the same folder to
    resume."""


class SurrogateError(Error, ValueError):
    """A surrogate cannot be read, or a point is outside it (an unknown input, a value
    outside an input's support)."""
