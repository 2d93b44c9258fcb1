"""The sequential study, reduced: a first campaign in one IK branch of an independently
simulated UR10, augmented to separate the diagnosis' candidates; the new poses leave the
branch, the own-weight deflection becomes detectable at a smaller size and is less absorbed,
and the held-out error in every branch falls."""
from studies.sequential.report import markdown
from studies.sequential.study import run


def test_augmenting_lowers_the_held_out_error(tmp_path):
    s = run(tmp_path, n_first=100, k=10, n_candidates=500, n_held=40, max_steps=1,
            control=False)
    if "skipped" in s:
        import pytest
        pytest.skip(s["skipped"])
    a = s["augment"]
    assert a["poses_outside_the_branch"] >= 5
    assert a["own_weight_min_detectable_after"] < a["own_weight_min_detectable_before"]
    assert a["own_weight_absorbed_after"] < a["own_weight_absorbed_before"]
    first, after = s["refine_first"], s["refine_augmented"]
    assert after["held_out_rms_3d_mm"] < first["held_out_rms_3d_mm"]
    assert "held-out 3-D RMS" in markdown(s)
