"""Figures drawn in a child process while the command computes.

Importing matplotlib and drawing a grid of scatter plots take 0.5–1 s, as
long as a whole 60-pose diagnosis. A :class:`FigureWorker` starts a child
Python at once; the child imports matplotlib while the parent builds its
model and fits, then draws each figure it is sent
(:mod:`doe_calib.report.figures` or :mod:`doe_calib.report.diagnosis_figures`
functions of plain arrays and numbers) and saves it as PNG. On two or more
cores the figure costs the command no time; on one core it costs what it
did in-process. :meth:`FigureWorker.close` waits for the child and raises
:class:`~doe_calib.errors.DoeCalibError` naming the file a figure could not
be written to.

``python -m doe_calib.report.figure_worker`` is the child: it reads pickled
jobs from its standard input until end of file.
"""
from __future__ import annotations

import os
import pickle
import subprocess
import sys
from pathlib import Path

from doe_calib.errors import DoeCalibError

#: The modules whose figure functions a job may name.
MODULES = ("doe_calib.report.figures", "doe_calib.report.diagnosis_figures")


class FigureWorker:
    """A child process that draws figures and saves them as PNG files.

    Use it as a context manager: leaving the block without an exception waits
    for every figure (:meth:`close`); with one, the child is stopped.

    >>> with FigureWorker() as worker:                       # doctest: +SKIP
    ...     worker.draw("residual_scatter", "residuals.png", norms_mm, columns)
    """

    def __init__(self):
        self._paths: list[str] = []
        # the child imports this very doe_calib, wherever the parent found it
        root = str(Path(__file__).resolve().parents[2])
        env = dict(os.environ, PYTHONPATH=os.pathsep.join(
            [root] + ([os.environ["PYTHONPATH"]] if os.environ.get("PYTHONPATH") else [])))
        try:
            self._child = subprocess.Popen([sys.executable, "-m", __name__], env=env,
                                           stdin=subprocess.PIPE, stdout=subprocess.DEVNULL,
                                           stderr=subprocess.PIPE)
        except OSError:  # no interpreter to start (an embedded Python): draw in-process
            self._child = None

    def draw(self, function: str, path, *args, dpi: int = 90, **kwargs) -> None:
        """Send one figure: ``function(*args, **kwargs)`` of :data:`MODULES`, saved to ``path``
        (PNG) at ``dpi`` dots per inch. Returns at once (without a child: when drawn)."""
        self._paths.append(str(path))
        if self._child is None:
            _draw(_figure_modules(), function, args, kwargs, path, dpi)
            return
        try:
            pickle.dump((function, args, kwargs, str(path), dpi), self._child.stdin,
                        protocol=pickle.HIGHEST_PROTOCOL)
            self._child.stdin.flush()
        except BrokenPipeError:  # the child has died: close() says why
            pass

    def close(self) -> None:
        """Wait until every figure is written; raise if one could not be."""
        if self._child is None:
            return
        try:
            self._child.stdin.close()
        except BrokenPipeError:
            pass
        err = self._child.stderr.read().decode(errors="replace").strip()
        if self._child.wait() != 0:
            last = err.splitlines()[-1] if err else f"exit status {self._child.returncode}"
            raise DoeCalibError(f"could not write the figure(s) {', '.join(self._paths)}: "
                                f"{last}")

    def __enter__(self) -> "FigureWorker":
        return self

    def __exit__(self, kind, error, trace) -> None:
        if kind is None:
            self.close()
        elif self._child is not None:
            self._child.kill()
            self._child.wait()


def _figure_modules() -> list:
    import importlib

    return [importlib.import_module(m) for m in MODULES]


def _draw(modules, function, args, kwargs, path, dpi) -> None:
    home = next((m for m in modules if hasattr(m, function)), None)
    if home is None:
        raise DoeCalibError(f"no figure function {function!r} in {', '.join(MODULES)}")
    try:
        getattr(home, function)(*args, **kwargs).savefig(path, dpi=dpi)
    except OSError as e:
        raise DoeCalibError(f"cannot write {Path(path)}: {e.strerror or e}") from None


def _warm_up(figures) -> None:
    """Draw a small throwaway figure to memory while the parent computes: a renderer's first
    figure (fonts, log axes, a legend) takes half as long again as the next one."""
    import io

    fig = figures.new_figure(4, 3)
    ax = fig.subplots()
    ax.plot([1, 2, 3], [1, 10, 100], "o-", label="warm-up")
    ax.set_yscale("log")
    ax.set_title("warm-up")
    ax.legend(fontsize=8)
    fig.savefig(io.BytesIO(), format="png", dpi=90)


def _serve(stream) -> None:
    """Draw and save every job read from ``stream`` until its end."""
    if hasattr(os, "nice"):  # the command's own threads first: the figure takes idle time
        os.nice(10)
    modules = _figure_modules()  # matplotlib, while the parent fits
    _warm_up(modules[0])
    while True:
        try:
            function, args, kwargs, path, dpi = pickle.load(stream)
        except EOFError:
            return
        _draw(modules, function, args, kwargs, path, dpi)


if __name__ == "__main__":
    try:
        _serve(sys.stdin.buffer)
    except DoeCalibError as e:
        print(e, file=sys.stderr)
        sys.exit(1)
    # every figure is written (savefig closed its file): leave without the interpreter's
    # teardown of matplotlib, which the parent would otherwise wait for
    sys.stderr.flush()
    os._exit(0)
