"""The real TIAGo sessions reduced to one point, through the commands a user runs (skipped
without the data)."""
import pytest

from studies.tiago_mocap.robot import DEFAULT_DATA, tiago_urdf
from studies.tiago_single_point.study import reduce_to_point, run

DATA = DEFAULT_DATA / "csv"
pytestmark = pytest.mark.skipif(not DATA.is_dir() or tiago_urdf() is None,
                                reason="tiago-mocap data or example-robot-data not available")


def test_one_point_of_the_tracked_body_predicts_a_held_out_session(tmp_path):
    """One fold of results/tiago_single_point.md without refine: a single point calibrates the
    arm's reach about as well as four points do at that point, and says what it cannot see."""
    tool, files = reduce_to_point(DATA, tmp_path, "BL")
    assert tool.read_text().count("BL") == 1 and "TL" not in tool.read_text()
    assert all(",BL," in f.read_text() and ",TL," not in f.read_text() for f in files)
    out = run(tiago_urdf(), DATA, tmp_path / "out", tmp_path, "BL", max_steps=0, folds=[3])
    fold = out["folds"][0]["held_out"]
    four, one = fold["four_points_at_point"]["rms_3d_mm"], fold["one_point"]["rms_3d_mm"]
    assert fold["one_point"]["readings"] == fold["four_points_at_point"]["readings"] > 30
    assert 1.0 < four < 5.0 and one < 1.5 * four, fold
    assert "one reflector (BL) cannot see" in out["folds"][0]["unseen"][0]
    assert (tmp_path / "out" / "tiago_single_point.md").read_text().count("| mocap_") == 1
