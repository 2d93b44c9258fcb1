"""Each design pose's clearance (design/candidates/clearances.py), the meshes measured only where
the hulls do not clear a pair, is the one the meshes' distances of every pair give: the same pair
and distance to the last digit at free poses of the UR5 and KR 270 cells (with their tool and a
payload), and the same distance to 1e-4 where a pose is too close."""
import numpy as np
from test_collision_bounds import _limits, cell  # noqa: F401 (the fixture)

from doe_calib.collision import Workspace, clearance, too_close
from doe_calib.design.candidates.clearances import pose_clearances


def _poses(cm, robot, n=300, seed=4):
    lo, hi = _limits(robot)
    return np.random.default_rng(seed).uniform(lo, hi, (n, robot.n_joints))


def test_clearances_are_those_of_every_pair_at_free_poses(cell):  # noqa: F811
    robot, cm = cell
    q = _poses(cm, robot)
    q = q[too_close(cm, q) < 0][:40]
    assert len(q) >= 20
    ws = Workspace(cm)
    every = tuple((c.mm, c.pair) for c in (clearance(cm, pose, ws) for pose in q))
    assert pose_clearances(cm, q) == every


def test_a_pose_too_close_is_reported_too_close(cell):  # noqa: F811
    """Where bodies overlap, coal's depth depends on its previous call (the full computation's
    too): the same to 1e-4 of the depth."""
    robot, cm = cell
    q = _poses(cm, robot, 120, 5)
    q = q[too_close(cm, q) >= 0][:10]
    assert len(q)
    for (mm, _), pose in zip(pose_clearances(cm, q), q):
        c = clearance(cm, pose, Workspace(cm))
        assert np.isclose(mm, c.mm, rtol=1e-4, atol=1e-3) and mm < 1000 * c.required
