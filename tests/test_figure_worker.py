"""Figures drawn by the child process are the in-process figures, byte for byte."""
from types import SimpleNamespace

import numpy as np
import pytest

from doe_calib.errors import DoeCalibError
from doe_calib.report.diagnosis_figures import error_falling
from doe_calib.report.figure_worker import FigureWorker
from doe_calib.report.figures import residual_scatter


def _columns(k=90):
    rng = np.random.default_rng(3)
    return (np.abs(rng.normal(0.0, 0.02, k)),
            [(f"q{j + 1} (deg)", rng.uniform(-170, 170, k)) for j in range(5)])


def test_child_draws_the_same_png_as_in_process(tmp_path):
    norms, columns = _columns()
    steps = [SimpleNamespace(added=None, rms_mm=1.9, cv_rms_mm=1.95, validation_rms_mm=None),
             SimpleNamespace(added="cyclic(j3)", rms_mm=0.03, cv_rms_mm=0.031,
                             validation_rms_mm=None)]
    with FigureWorker() as worker:
        worker.draw("residual_scatter", tmp_path / "a.png", norms, columns)
        worker.draw("error_falling", tmp_path / "b.png", steps, 0.02, dpi=60)
    residual_scatter(norms, columns).savefig(tmp_path / "a_ref.png", dpi=90)
    error_falling(steps, 0.02).savefig(tmp_path / "b_ref.png", dpi=60)
    for name in ("a", "b"):
        got = (tmp_path / f"{name}.png").read_bytes()
        assert got[:8] == b"\x89PNG\r\n\x1a\n"
        assert got == (tmp_path / f"{name}_ref.png").read_bytes()


def test_unwritable_figure_is_an_error_naming_the_file(tmp_path):
    norms, columns = _columns()
    target = tmp_path / "no such folder" / "r.png"
    with pytest.raises(DoeCalibError, match="no such folder") as caught:
        with FigureWorker() as worker:
            worker.draw("residual_scatter", target, norms, columns)
    assert "r.png" in str(caught.value)
    with pytest.raises(DoeCalibError, match="no figure function 'nonsense'"):
        with FigureWorker() as worker:
            worker.draw("nonsense", tmp_path / "x.png")


def test_an_error_in_the_command_stops_the_child(tmp_path):
    with pytest.raises(RuntimeError):
        with FigureWorker() as worker:
            child = worker._child
            raise RuntimeError("the fit failed")
    assert child.poll() is not None  # stopped, not left drawing
    assert not (tmp_path / "r.png").exists()


def test_without_an_interpreter_to_start_the_figure_is_drawn_in_process(tmp_path, monkeypatch):
    import subprocess

    def no_child(*args, **kwargs):
        raise FileNotFoundError("no python here")

    monkeypatch.setattr(subprocess, "Popen", no_child)
    norms, columns = _columns()
    with FigureWorker() as worker:
        worker.draw("residual_scatter", tmp_path / "a.png", norms, columns)
        assert (tmp_path / "a.png").exists()  # drawn at once
    residual_scatter(norms, columns).savefig(tmp_path / "ref.png", dpi=90)
    assert (tmp_path / "a.png").read_bytes() == (tmp_path / "ref.png").read_bytes()
    with pytest.raises(DoeCalibError, match="no such folder"):
        with FigureWorker() as worker:
            worker.draw("residual_scatter", tmp_path / "no such folder" / "r.png", norms,
                        columns)
