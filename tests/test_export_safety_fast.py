"""A program's collision check with the fast move check (poses skipped) against the
reference (every pair at every pose of every move, ``Workspace(cm, bounded=False)``): the same
routes, via-points, planned paths, colliding moves and count of poses, on KR 270 programs that go
through the floor (routed through a free pose, planned, or colliding)."""
import numpy as np
import pytest
from test_export_safety import FLOOR_A, FLOOR_B, HOME, _constructed

import doe_calib.export.safety as safety
from doe_calib.collision import Workspace, build_collision_model
from doe_calib.export import Plan, check_program, moves, program_models


def _checked(design, cm, planner, monkeypatch, bounded):
    with monkeypatch.context() as m:
        m.setattr(safety, "Workspace", lambda model: Workspace(model, bounded=bounded))
        return check_program(moves(design, Plan(order="design")),
                             program_models([], lambda loads: cm), design.robot,
                             planner=planner)


def _same(fast, dense):
    assert (fast.moves, fast.samples, fast.routed, fast.collisions, fast.blocked) == \
        (dense.moves, dense.samples, dense.routed, dense.collisions, dense.blocked)
    for a, b in zip(fast.visits, dense.visits):
        assert len(a.via) == len(b.via)
        for u, v in zip(a.via, b.via):
            assert np.array_equal(u.urdf, v.urdf) and u.why == v.why


@pytest.mark.parametrize("poses, planner, routed, colliding", [
    ([FLOOR_A, FLOOR_B, HOME], False, 1, 0),   # routed through home
    ([FLOOR_A, FLOOR_B, FLOOR_A, FLOOR_B], False, 0, 3),  # colliding, back and forth
    ([FLOOR_A, FLOOR_B], True, 1, 0),          # planned
])
def test_fast_program_check_is_the_reference_one(tmp_path, monkeypatch, poses, planner, routed,
                                                 colliding):
    design, _ = _constructed(tmp_path, poses, "program")
    cm = build_collision_model(design.robot, design.tool)
    fast = _checked(design, cm, planner, monkeypatch, True)
    dense = _checked(design, cm, planner, monkeypatch, False)
    assert len(fast.routed) == routed and len(fast.collisions) == colliding
    _same(fast, dense)


@pytest.mark.parametrize("poses, planner", [
    ([FLOOR_A, FLOOR_B, HOME, FLOOR_A, FLOOR_B], False),  # routed and colliding moves
    ([FLOOR_A, FLOOR_B, FLOOR_A], True),                   # planned, in worker processes
])
def test_moves_checked_in_processes_are_the_moves_checked_here(tmp_path, poses, planner):
    design, _ = _constructed(tmp_path, poses, "program")
    cm = build_collision_model(design.robot, design.tool)
    visits = moves(design, Plan(order="design"))
    here = check_program(visits, program_models([], lambda loads: cm), design.robot,
                         planner=planner, workers=1)
    there = check_program(visits, program_models([], lambda loads: cm), design.robot,
                          planner=planner, workers=2)
    assert here.routed or here.collisions  # the case has moves to route or refuse
    _same(there, here)
