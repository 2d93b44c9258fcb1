"""Reachability through stepping stones (design/candidates/reachability.py): in the UR5 cell
every pose a straight move or a planned path from home joins on its own is joined, at the same
angles where that was its first try, also with the stepping stones of an earlier check; a pose is
refused only where the planner from home finds no path either; and a path planned only to exist
(plan_move(shorten=False)) is free at 1°."""
import numpy as np
import pytest
from test_collision_bounds import _ur5

from doe_calib import Robot, Tool, examples
from doe_calib.collision import (PlannerSettings, blocked_beams, build_collision_model,
                                 check_path, check_segment, plan_move, too_close, unplannable)
from doe_calib.design import read_constraints
from doe_calib.design.candidates.reachability import NO_PATH, nearest_equivalent, unreachable


@pytest.fixture(scope="module")
def cell():
    robot, tool = Robot.from_urdf(_ur5()), Tool.from_yaml(examples.UR_TOOL_YAML)
    constraints = read_constraints(examples.UR5_CELL_YAML, robot, tool)
    cm = build_collision_model(robot, tool, (), constraints, planner=PlannerSettings())
    lower, upper = constraints.bounds(robot)
    rng = np.random.default_rng(3)
    q = rng.uniform(np.maximum(lower, -2 * np.pi), np.minimum(upper, 2 * np.pi), (400, 6))
    return robot, cm, lower, upper, q[too_close(cm, q) < 0][:12]


def _on_its_own(cm, home, robot, lower, upper, pose):
    """One pose from home alone: (reason or None, the angles, whether they are its first try)."""
    blocked = blocked_beams(cm, pose)
    if blocked:
        return f"line of sight: blocked by {blocked[0].body}", pose, True
    near = nearest_equivalent(pose, home, robot, lower, upper)
    for n, t in enumerate([pose] + ([near] if not np.allclose(near, pose) else [])):
        if check_segment(cm, home, t, cm.move_margins).free or plan_move(
                cm, home, t, settings=cm.planner) is not None:
            return None, t, n == 0
    return NO_PATH, pose, True


def test_poses_joined_from_home_alone_are_joined_and_refused_ones_are_refused_alone(cell):
    robot, cm, lower, upper, q = cell
    home = np.zeros(6)
    assert len(q) >= 10
    found = unreachable(cm, q, home, robot, lower, upper, workers=1)
    alone = [_on_its_own(cm, home, robot, lower, upper, pose) for pose in q]
    for (why, used), (why_alone, used_alone, first) in zip(found, alone):
        if why_alone is None or why is not None:
            assert why == why_alone
        if why_alone is None and first:
            np.testing.assert_array_equal(used, used_alone)
    assert sum(w is None for w, _ in found) >= 6
    # measured: the first pose (−298°, −189°, …) is joined through another pose, while the
    # planner's search from home gives up on it (its equivalent is proven blocked)
    assert found[0][0] is None and alone[0][0] == NO_PATH


def test_stepping_stones_carried_from_an_earlier_check_keep_what_home_alone_joins(cell):
    """A second check given the positions the first joined (as reachable_choice does)."""
    robot, cm, lower, upper, q = cell
    home, joined = np.zeros(6), []
    first = unreachable(cm, q[:5], home, robot, lower, upper, workers=1, joined=joined)
    known = len(joined)
    assert known >= sum(w is None for w, _ in first)
    found = unreachable(cm, q[5:], home, robot, lower, upper, joined=joined)
    assert len(joined) > known
    for (why, used), pose in zip(found, q[5:]):
        why_alone, used_alone, first_try = _on_its_own(cm, home, robot, lower, upper, pose)
        if why_alone is None or why is not None:
            assert why == why_alone
        if why_alone is None and first_try:
            np.testing.assert_array_equal(used, used_alone)


def test_a_path_planned_only_to_exist_is_free_at_one_degree(cell):
    robot, cm, lower, upper, q = cell
    home = np.zeros(6)
    planned = ((p, plan_move(cm, home, p, settings=cm.planner)) for p in q
               if not check_segment(cm, home, p, cm.move_margins).free
               and not unplannable(cm, home, p))
    pose, short = next((p, s) for p, s in planned if s is not None)
    raw = plan_move(cm, home, pose, settings=cm.planner, shorten=False)
    assert raw is not None
    assert len(raw.via) >= len(short.via)
    hit, samples = check_path(cm, np.array([home, *raw.via, pose]), cm.move_margins)
    assert hit is None and samples == raw.samples
