"""Progress of long work: the one protocol, and a bar on stderr that follows it.

Every long-running function takes ``progress``, a callable it calls as
``progress(done, total, note)``: ``done`` an int (steps finished), ``total`` an
int or None when unknown, ``note`` a str (the stage's name or a figure, e.g.
a cost). :class:`Progress` is such a callable, drawn on the terminal.
"""
from __future__ import annotations

import sys
import time


class Progress:
    """A one-line progress bar: ``label done/total [####    ] elapsed``.

    Quiet unless ``stream`` is a terminal, so logs and pipes stay clean.

    Examples
    --------
    >>> bar = Progress(100, "Monte Carlo")
    >>> for k in range(100):
    ...     bar(k + 1, None, "")
    >>> bar.close()
    """

    def __init__(self, total: int, label: str, stream=None, width: int = 30):
        self.total, self.label, self.width = max(int(total), 1), label, width
        self.stream = sys.stderr if stream is None else stream
        self.active = bool(getattr(self.stream, "isatty", lambda: False)())
        self.start = time.perf_counter()

    def __call__(self, done: int, total: int | None, note: str) -> None:
        """Show ``done`` of ``total`` finished (None: the total kept), with ``note`` (a stage
        or a figure): the protocol's ``progress(done, total, note)``."""
        if total is not None:
            self.total = max(int(total), 1)
        if not self.active:
            return
        fill = int(self.width * min(done, self.total) / self.total)
        elapsed = time.perf_counter() - self.start
        text = (f"\r{self.label} {done}/{self.total} [{'#' * fill:<{self.width}}] "
                f"{elapsed:5.1f} s {note}")
        self.stream.write(text)
        self.stream.flush()

    def close(self) -> None:
        """End the line (only if anything was drawn)."""
        if self.active:
            self.stream.write("\n")
            self.stream.flush()
