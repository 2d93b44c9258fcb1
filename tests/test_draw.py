"""Random candidates (design/candidates/draw.py): each round judged in shares, in this process
or in forked ones, keeps the candidates and counts the drawn and removed poses as one
process judging each round whole does, in the UR5 cell with its collision model and tracker
and with its constraints alone."""
import numpy as np
import pytest
from test_collision_bounds import _ur5

from doe_calib import Robot, Tool, build_model, examples
from doe_calib.collision import build_collision_model
from doe_calib.design import read_constraints
from doe_calib.design.candidates import draw
from doe_calib.design.candidates.feasibility import build_feasibility
from doe_calib.design.problem import LoadCase


@pytest.fixture(scope="module")
def ur5_cell():
    robot, tool = Robot.from_urdf(_ur5()), Tool.from_yaml(examples.UR_TOOL_YAML)
    constraints = read_constraints(examples.UR5_CELL_YAML, robot, tool)
    load = LoadCase(3.0, (0.0, 0.0, 0.08), radius=0.04)
    model = build_model(robot, tool, "joint_offset+geometry")
    feasibility = build_feasibility(model, model.nominal().values, constraints, [load])
    collision = build_collision_model(robot, tool, (load,), constraints, samples=100,
                                      planner=None)
    return robot, feasibility, collision


@pytest.mark.parametrize("with_collision", [True, False])
def test_candidates_judged_in_shares_are_judged_as_one(ur5_cell, with_collision, monkeypatch):
    robot, feasibility, collision = ur5_cell
    collision = collision if with_collision else None
    n = 40 if with_collision else 300

    def drawn(share, workers):
        monkeypatch.setattr(draw, "_DRAWN_SHARE", share)
        monkeypatch.setattr(draw, "_DRAWN_SHARE_FREE", share)
        return draw.feasible_candidates(feasibility, robot, n, np.random.default_rng(3),
                                        collision, workers=workers)

    whole = drawn(10**9, 1)  # each round judged at once: the reference
    assert len(whole.q) == n and whole.drawn > 2 * n  # several rounds, most poses removed
    if with_collision:
        assert any(k.startswith("collision: ") for k in whole.removed)
        assert any(k.startswith("line of sight: ") for k in whole.removed)
    for shares in (drawn(15, 1), drawn(15, 2)):  # in shares here, then in forked processes
        assert np.array_equal(shares.q, whole.q) and shares.drawn == whole.drawn
        assert list(shares.removed.items()) == list(whole.removed.items())
