"""Poses far outside the noise are named with their χ² p-value and worst reading's line."""
import numpy as np
import pytest
from scipy.special import chdtrc

from doe_calib.diagnosis.residuals import Residuals, flagged_poses


def _residuals(rng, n_poses=400, per_pose=6, sigma=2e-5, bad=(17, 230), size=(8.0, 5.0)):
    pose = np.repeat(np.arange(n_poses), per_pose)
    weighted = rng.normal(size=(len(pose), 3))
    for g, s in zip(bad, size):  # one reading of each bad pose is s σ off in x, y and z
        weighted[g * per_pose + 2] += s
    pose_ids = tuple(f"P{g + 1}" for g in pose)
    return Residuals(weighted * sigma, weighted, pose, pose_ids)


def test_the_gross_poses_are_named_with_scipy_p_values_and_their_worst_line():
    rng = np.random.default_rng(5)
    res = _residuals(rng)
    lines = np.arange(len(res.pose)) + 2  # line 1 is the header
    dof_fraction = 0.9
    out = flagged_poses(res, dof_fraction, lines=lines)
    assert [f["pose"] for f in out] == ["P18", "P231"]  # by χ²/dof, the larger first
    for f, g in zip(out, (17, 230)):
        mine = slice(g * 6, g * 6 + 6)
        t = float((res.weighted[mine] ** 2).sum())
        dof = 6 * 3 * dof_fraction
        assert f["chi2"] == pytest.approx(t, rel=1e-12)
        assert f["chi2_per_dof"] == pytest.approx(t / dof, rel=1e-12)
        assert f["p_value"] == pytest.approx(chdtrc(dof, t) * 400, rel=1e-10)
        assert f["worst_line"] == g * 6 + 2 + 2
        assert f["rms_mm"] == pytest.approx(np.sqrt(np.mean(res.error[mine] ** 2)) * 1e3)


def test_a_whole_model_off_names_no_pose():
    rng = np.random.default_rng(6)
    res = _residuals(rng, bad=(), size=())
    scaled = Residuals(res.error * 3, res.weighted * 3, res.config, res.pose)
    assert flagged_poses(scaled, 0.9) == []  # every pose 9× the noise: none stands out
