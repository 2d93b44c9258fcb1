"""On a terminal, long commands show their progress through the one protocol,
``progress(done, total, note)``; tests otherwise run without a terminal and never draw it."""
import io
import sys

from doe_calib import examples
from doe_calib.cli import main

COMMON = ["--robot", examples.ROBOT_URDF, "--tool", examples.TOOL_YAML]


class Terminal(io.StringIO):
    """A stderr that says it is a terminal."""

    def isatty(self) -> bool:
        return True


def _on_terminal(monkeypatch, argv) -> str:
    err = Terminal()
    monkeypatch.setattr(sys, "stderr", err)
    assert main(argv) == 0, err.getvalue()
    return err.getvalue()


def test_identify_and_design_draw_their_progress_on_a_terminal(monkeypatch, tmp_path):
    data = tmp_path / "m.csv"
    assert main(["simulate", *COMMON, "--model", "joint_offset", "--poses", "12", "--seed", "3",
                 "--sigma", "0.02", "--out", str(data)]) == 0
    shown = _on_terminal(monkeypatch, ["identify", *COMMON, "--model", "joint_offset",
                                       "--data", str(data), "--sigma", "0.02",
                                       "--out", str(tmp_path / "r.json")])
    assert "Levenberg–Marquardt" in shown and "/200)" in shown
    shown = _on_terminal(monkeypatch, ["design", *COMMON, "--model", "joint_offset",
                                       "--poses", "8", "--candidates", "300", "--seed", "1",
                                       "--out", str(tmp_path / "d.json")])
    assert "\r" in shown and len(shown.strip()) > 0
