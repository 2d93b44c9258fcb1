"""Tasks over collision models in forked processes (runtime/forked.py) give what one process
gives: a plain function, tasks handed over while the caller works, and the design's reachability
of UR5 poses in its cell (planned: proofs in the processes while this one plans)."""
import multiprocessing

import numpy as np
from test_collision_bounds import _ur5

from doe_calib import Robot, Tool, examples
from doe_calib.collision import PlannerSettings, build_collision_model, too_close
from doe_calib.design import read_constraints
from doe_calib.design.candidates.reachability import unreachable
from doe_calib.runtime.forked import forked_map, forked_pool


def _square_plus(shared, i):
    offset, values = shared
    return (i, values[i] ** 2 + offset)


def test_forked_results_are_in_task_order():
    shared = (0.5, np.arange(7.0))
    here = forked_map(_square_plus, shared, 7, workers=1)
    assert here == [(i, i * i + 0.5) for i in range(7)]
    assert forked_map(_square_plus, shared, 7, workers=2) == here


def _scaled(shared, item):
    return shared[0] * item


def test_a_pool_gives_each_item_in_order_while_the_caller_works():
    for processes in (0, 1, 2):
        with forked_pool((3.0,), processes) as results:
            first = list(results(_scaled, range(5)))
            later = results(_scaled, (v + 10 for v in first))  # from what the first learnt
            assert [next(later) for _ in range(5)] == [3.0 * (v + 10) for v in first]
        assert first == [0.0, 3.0, 6.0, 9.0, 12.0]


def _forked_inside(i):
    return forked_map(_square_plus, (0.5, np.arange(7.0)), 7, workers=2)


def test_a_daemonic_worker_maps_in_itself():
    """A pool's worker may not have children: its forked_map runs the tasks in itself."""
    with multiprocessing.get_context("fork").Pool(1) as pool:
        inside = pool.map(_forked_inside, [0])[0]
    assert inside == [(i, i * i + 0.5) for i in range(7)]


def test_reachability_in_processes_is_reachability_in_one():
    robot, tool = Robot.from_urdf(_ur5()), Tool.from_yaml(examples.UR_TOOL_YAML)
    cell = read_constraints(examples.UR5_CELL_YAML, robot, tool)
    cm = build_collision_model(robot, tool, (), cell, planner=PlannerSettings(checks=400))
    rng = np.random.default_rng(5)
    lower, upper = cell.bounds(robot)
    q = rng.uniform(np.maximum(lower, -np.pi), np.minimum(upper, np.pi), (60, robot.n_joints))
    q = q[too_close(cm, q) < 0][:10]  # free poses
    assert len(q) >= 6
    one = unreachable(cm, q[1:], q[0], robot, lower, upper, workers=1)
    two = unreachable(cm, q[1:], q[0], robot, lower, upper, workers=2)
    assert [w for w, _ in one] == [w for w, _ in two]
    assert all(np.array_equal(a, b) for (_, a), (_, b) in zip(one, two))
    assert any(w is None for w, _ in one)


def test_reachability_with_proofs_and_plans_in_processes_is_reachability_in_one():
    """Poses of the cell that need the planner (equivalents, stepping stones, proofs): the
    verdicts and the angles do not depend on the processes."""
    robot, tool = Robot.from_urdf(_ur5()), Tool.from_yaml(examples.UR_TOOL_YAML)
    cell = read_constraints(examples.UR5_CELL_YAML, robot, tool)
    cm = build_collision_model(robot, tool, (), cell, planner=PlannerSettings())
    lower, upper = cell.bounds(robot)
    rng = np.random.default_rng(3)
    q = rng.uniform(np.maximum(lower, -2 * np.pi), np.minimum(upper, 2 * np.pi), (400, 6))
    q = q[too_close(cm, q) < 0][:12]
    one = unreachable(cm, q, np.zeros(6), robot, lower, upper, workers=1)
    two = unreachable(cm, q, np.zeros(6), robot, lower, upper, workers=2)
    assert [w for w, _ in one] == [w for w, _ in two]
    assert all(np.array_equal(a, b) for (_, a), (_, b) in zip(one, two))
    assert sum(w is None for w, _ in one) >= 6
