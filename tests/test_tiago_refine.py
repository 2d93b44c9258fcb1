"""The real TIAGo sessions through the commands a user runs (skipped without the data)."""
import pytest

from studies.tiago_mocap.robot import DEFAULT_DATA, tiago_urdf
from studies.tiago_refine.study import held_out_session, sessions

DATA = DEFAULT_DATA / "csv"
pytestmark = pytest.mark.skipif(not DATA.is_dir() or tiago_urdf() is None,
                                reason="tiago-mocap data or example-robot-data not available")


def test_refine_on_three_sessions_predicts_the_fourth_better(tmp_path):
    """One fold of results/tiago_refine.md, one effect: readings past the torso limit are
    accepted, the effect is chosen on the training sessions, the held-out error falls."""
    assert len(sessions(DATA)) == 4
    fold = held_out_session(tiago_urdf(), DATA, 3, tmp_path, max_steps=1)
    assert len(fold["steps"]) == 2 and fold["steps"][1]["added"], fold
    start, refined = (fold["held_out"][t]["rms_3d_mm"] for t in ("start", "refined"))
    assert 2.0 < start < 4.0  # the geometric calibration of this arm: ≈ 2.9 mm held out
    assert refined < 0.9 * start, fold
    assert fold["steps"][1]["held_out_rms_3d_mm"] == pytest.approx(refined, rel=1e-6)
