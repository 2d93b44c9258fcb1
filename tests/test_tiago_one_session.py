"""FIGAROH's one-session TIAGo protocol through the commands a user runs: plain ``identify``
predicts the other sessions within the issue's bound (skipped without the data)."""
import pytest

from studies.tiago_mocap.robot import DEFAULT_DATA, tiago_urdf
from studies.tiago_one_session.study import run

DATA = DEFAULT_DATA / "csv"
pytestmark = pytest.mark.skipif(not DATA.is_dir() or tiago_urdf() is None,
                                reason="tiago-mocap data or example-robot-data not available")


def test_one_session_from_one_point_predicts_the_other_sessions(tmp_path):
    """37 postures of BL for 33 separable parameters: the whole fit over-fits (3.88 mm on the
    three other sessions); identify as it comes leaves the weakest at nominal, says which,
    and predicts them within 2.90 mm (FIGAROH's smaller set: 2.93 mm)."""
    out = run(tiago_urdf(), DATA, tmp_path / "out", tmp_path, points=("BL",), rich=False)
    bl = out["points"][0]
    whole, chosen = bl["none"], bl["cv"]
    assert sum(e["readings"] for e in chosen["held_out"].values()) > 150
    assert whole["free"] == 33 and whole["pooled_rms_3d_mm"] > 3.5, whole
    assert chosen["pooled_rms_3d_mm"] <= 2.90, chosen
    left = chosen["selection"]["left_at_nominal"]
    assert left and chosen["free"] == whole["free"] - len(left)
    rms = chosen["selection"]["predicted_rms_3d_mm"]
    assert rms[-1] < rms[0]
    assert "| BL | 3.88 (33) |" in (tmp_path / "out" / "tiago_one_session.md").read_text()
