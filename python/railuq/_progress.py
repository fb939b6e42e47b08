"""Progress of a running study and the library's messages, in a terminal and in Jupyter.

With ``progress=True`` a study shows a bar (tqdm's, when tqdm is installed: ``tqdm.auto``
draws a widget in Jupyter) or else plain text on ``sys.stderr`` (one line redrawn in a
terminal; a line every tenth of the points or every 10 s elsewhere, e.g. in a notebook or a
log), and prints the library's notes and warnings there too, as the command line does.
With ``progress=False`` nothing is printed: the messages go to the ``railuq`` logger
(warnings at WARNING, notes at INFO).
"""
from __future__ import annotations

import sys
import time

from . import _railuq

# typing, logging, tempfile and difflib are imported where they are used: `import railuq`
# stays cheap (the Python path's cost over the command line is measured in `make bench`).
TYPE_CHECKING = False
if TYPE_CHECKING:
    from typing import Any, Optional


def _log(line: str) -> None:
    """Logs ``line`` on the ``railuq`` logger: warnings and errors at WARNING, notes at INFO."""
    import logging

    level = logging.WARNING if "warning:" in line or "error:" in line else logging.INFO
    logging.getLogger("railuq").log(level, line)


def forward_messages(display: Optional["Display"], lines: Optional[list[str]] = None) -> None:
    """Shows (``display``) or logs the library's messages (``lines``, else those queued)."""
    for line in _railuq.take_messages() if lines is None else lines:
        if display is not None:
            display.write(line)
        else:
            _log(line)


class Display:
    """A progress display: tqdm if installed, else text on stderr."""

    def __init__(self, name: str) -> None:
        self.name = name
        self.total = 0
        self.done = 0
        self.bar: Any = None
        self.started = time.monotonic()
        self.last_line = (0.0, -1)
        self.tty = bool(getattr(sys.stderr, "isatty", lambda: False)())
        self.redrawn = False
        try:
            from tqdm.auto import tqdm
        except ImportError:
            tqdm = None
        self.tqdm = tqdm

    def update(self, done: int, total: int, messages: list[str]) -> None:
        forward_messages(self, messages)
        if total != self.total:  # a new batch (a suite's next variant)
            self._close()
            self.total, self.done, self.started = total, 0, time.monotonic()
            self.last_line = (self.started, -1)
            if total > 0 and self.tqdm is not None:
                self.bar = self.tqdm(total=total, unit="point", desc=self.name,
                                     file=sys.stderr, leave=True)
        if total == 0 or done == self.done:
            return
        if self.bar is not None:
            self.bar.update(done - self.done)
        else:
            self._text(done)
        self.done = done

    def _text(self, done: int) -> None:
        elapsed = time.monotonic() - self.started
        left = (f", ~{elapsed * (self.total - done) / done:.0f} s left"
                if 0 < done < self.total else "")
        line = (f"{self.name}: {done}/{self.total} points ({100 * done / self.total:.0f} %), "
                f"{elapsed:.1f} s{left}")
        if self.tty:
            sys.stderr.write("\r" + line + "\x1b[K")
            sys.stderr.flush()
            self.redrawn = True
            return
        tenth = done * 10 // self.total
        last_t, last_tenth = self.last_line
        now = time.monotonic()
        if done == self.total or tenth > last_tenth or now - last_t >= 10.0:
            print(line, file=sys.stderr, flush=True)
            self.last_line = (now, tenth)

    def write(self, line: str) -> None:
        """A message, printed without garbling the bar."""
        if self.bar is not None:
            self.bar.write(line, file=sys.stderr)
            return
        if self.redrawn:
            sys.stderr.write("\r\x1b[K")
        print(line, file=sys.stderr, flush=True)
        if self.redrawn and self.total:
            self._text(self.done)

    def _close(self) -> None:
        if self.bar is not None:
            self.bar.close()
            self.bar = None
        if self.redrawn:
            sys.stderr.write("\n")
            sys.stderr.flush()
            self.redrawn = False

    def close(self) -> None:
        self._close()
