"""Progress of long work on the terminal: a bar on stderr, silent when stderr is not a terminal."""
from __future__ import annotations

import sys
import time


class Progress:
    """A one-line progress bar: ``label done/total [####    ] elapsed``.

    Quiet unless ``stream`` is a terminal (or ``force``), so logs and pipes stay clean.

    Examples
    --------
    >>> bar = Progress(100, "Monte Carlo")
    >>> for k in range(100):
    ...     bar.update(k + 1)
    >>> bar.close()
    """

    def __init__(self, total: int, label: str, stream=None, force: bool = False,
                 width: int = 30):
        self.total, self.label, self.width = max(int(total), 1), label, width
        self.stream = sys.stderr if stream is None else stream
        self.active = force or bool(getattr(self.stream, "isatty", lambda: False)())
        self.start = time.perf_counter()
        self.done = 0

    def update(self, done: int, note: str = "") -> None:
        """Show ``done`` of ``total`` finished, with an optional note (e.g. a duality gap)."""
        self.done = done
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

    def __call__(self, done: int, total: int | None = None) -> None:
        """Callback form ``progress(done, total)`` used by long-running functions."""
        if total is not None:
            self.total = max(int(total), 1)
        self.update(done)
