"""Motion planning (OMPL RRT-Connect), move clearance, tracker beams and pairs that never move:
each checked against an independent Pinocchio/coal model or plain numpy geometry."""
import math

import numpy as np
import pinocchio as pin
import pytest
from test_export_safety import FLOOR_A, FLOOR_B, KR270_ADJACENT, _geometry

from doe_calib import Robot, Tool, examples
from doe_calib.collision import (
    BEAM_RADIUS,
    PlannerSettings,
    blocked_beams,
    build_collision_model,
    check_segment,
    clearance,
    plan_move,
)
from doe_calib.design import read_constraints
from doe_calib.design.candidates.reachability import nearest_equivalent
from doe_calib.errors import ModelError

ONE_DEG = math.radians(1.0)


@pytest.fixture(scope="module")
def kr270():
    robot, tool = Robot.from_urdf(examples.ROBOT_URDF), Tool.from_yaml(examples.TOOL_YAML)
    return robot, tool, build_collision_model(robot, tool)


def test_planner_clears_a_move_through_the_floor_checked_independently(kr270):
    robot, tool, cm = kr270
    a, b = np.radians(FLOOR_A), np.radians(FLOOR_B)
    assert not check_segment(cm, a, b, cm.move_margins).free
    planned = plan_move(cm, a, b)
    assert planned is not None and len(planned.via) >= 1
    again = plan_move(cm, a, b)  # seeded: the same path
    assert np.allclose(np.array(planned.via), np.array(again.via))
    path = [a, *planned.via, b]
    assert all(np.all(q >= robot.lower) and np.all(q <= robot.upper) for q in path)
    model, geom = _geometry(robot.source, tool, KR270_ADJACENT)
    data, gdata = model.createData(), geom.createData()
    for qa, qb in zip(path[:-1], path[1:]):
        n = max(2, int(np.ceil(np.max(np.abs(qb - qa)) / ONE_DEG)) + 1)
        for t in np.linspace(0, 1, n):
            assert not pin.computeCollisions(model, data, geom, gdata, qa + t * (qb - qa), True)


def test_planner_gives_up_on_a_goal_in_collision(kr270):
    robot, _, cm = kr270
    into_floor = np.radians([0.0, 60.0, 100.0, 0.0, 0.0, 0.0])
    assert plan_move(cm, np.radians(FLOOR_A), into_floor, settings=PlannerSettings(time=0.2)) \
        is None


def test_move_clearance_is_half_the_pose_clearance_and_never_above_it(kr270):
    robot, tool, cm = kr270
    assert cm.move_clearance == pytest.approx(0.01) and cm.move_self_clearance == \
        pytest.approx(0.0025)
    assert set(cm.move_margins) <= {0.01, 0.0025}
    assert cm.summary()["move_clearance_mm"] == pytest.approx(10.0)
    with pytest.raises(ModelError, match="move clearance 30 mm is above the pose clearance"):
        build_collision_model(robot, tool, move_clearance=0.03)


def test_never_moving_pair_is_constant_and_not_reported():
    robot, tool = Robot.from_urdf(examples.ROBOT_URDF), Tool.from_yaml(examples.TOOL_YAML)
    constraints = read_constraints(examples.CELL_YAML, robot, tool)
    cm = build_collision_model(robot, tool, constraints=constraints)
    assert "link_1 vs floor" in cm.summary()["pairs_never_moving"]
    # independently: link_1's distance to the floor plane (z = 300 mm) over random poses
    model = pin.buildModelFromUrdf(str(robot.source))
    geom = pin.buildGeomFromUrdf(model, str(robot.source), pin.GeometryType.COLLISION)
    k = next(i for i, g in enumerate(geom.geometryObjects)
             if model.frames[g.parentFrame].name == "link_1")
    rng = np.random.default_rng(3)
    lows = []
    for q in rng.uniform(robot.lower, robot.upper, (20, 6)):
        data, gdata = model.createData(), geom.createData()
        pin.updateGeometryPlacements(model, data, geom, gdata, q)
        box = geom.geometryObjects[k].geometry
        box.computeLocalAABB()
        aabb = box.aabb_local
        corners = np.array([[x, y, z] for x in (aabb.min_[0], aabb.max_[0])
                            for y in (aabb.min_[1], aabb.max_[1])
                            for z in (aabb.min_[2], aabb.max_[2])])
        placed = gdata.oMg[k]
        lows.append(min((placed.rotation @ c + placed.translation)[2] for c in corners))
    assert np.ptp(lows) < 1e-9  # a turn about the vertical axis keeps its height
    for q in rng.uniform(robot.lower, robot.upper, (20, 6)):
        assert clearance(cm, q).pair != "link_1 vs floor"


def _segment_hits_box(p, r, lo, hi, radius):
    """Whether the segment p → r passes within ``radius`` of the box (numpy, sampled at 1 mm)."""
    t = np.linspace(0.0, 1.0, int(np.linalg.norm(r - p) / 0.001) + 2)[:, None]
    x = p + t * (r - p)
    outside = np.linalg.norm(np.maximum(np.maximum(lo - x, x - hi), 0.0), axis=1)
    return bool(np.min(outside) <= radius)


def test_beams_blocked_by_a_screen_agree_with_numpy(tmp_path):
    robot, tool = Robot.from_urdf(examples.ROBOT_URDF), Tool.from_yaml(examples.TOOL_YAML)
    cell = tmp_path / "cell.yaml"
    cell.write_text("cartesian:\n  keep_out:\n    - {name: screen, min: [2000, -300, 0], "
                    "max: [2050, 300, 3000]}\nline_of_sight:\n  tracker: [3000, 0, 1000]\n"
                    "  max_incidence: 89\n")
    constraints = read_constraints(cell, robot, tool)
    cm = build_collision_model(robot, tool, constraints=constraints)
    lo, hi = np.array([2.0, -0.3, 0.0]), np.array([2.05, 0.3, 3.0])
    tracker = np.array([3.0, 0.0, 1.0])
    model = pin.buildModelFromUrdf(str(robot.source))
    data = model.createData()
    fid = model.getFrameId(robot.flange)
    rng = np.random.default_rng(5)
    by_screen = agree = 0
    for q in rng.uniform(robot.lower, robot.upper, (60, 6)):
        pin.framesForwardKinematics(model, data, q)
        flange = data.oMf[fid]
        ours = {b.marker: b.body for b in blocked_beams(cm, q)}
        for name, p in zip(tool.names, tool.position_array):
            marker = flange.rotation @ p + flange.translation
            end = marker - (marker - tracker) / np.linalg.norm(marker - tracker) * (
                tool.marker_radius + BEAM_RADIUS)
            near = _segment_hits_box(tracker, end, lo, hi, BEAM_RADIUS + 0.002)
            far = _segment_hits_box(tracker, end, lo, hi, BEAM_RADIUS - 0.002)
            if near == far:  # clear of the boundary
                screen = ours.get(name) == "keep-out screen"
                # the screen is the first body found only when nothing else blocks earlier
                assert screen <= near
                if near and name not in ours:
                    pytest.fail(f"beam to {name} passes the screen at q = {q}")
                by_screen += screen
                agree += 1
    assert by_screen >= 5 and agree >= 150


def test_nearest_equivalent_turns_whole_turns_inside_the_bounds():
    robot = Robot.from_urdf(examples.ROBOT_URDF)
    lower, upper = np.full(6, -2 * np.pi), np.full(6, 2 * np.pi)
    q = np.radians([280.0, -300.0, 10.0, 350.0, -10.0, 0.0])
    out = nearest_equivalent(q, np.zeros(6), robot, lower, upper)
    assert np.allclose(np.degrees(out), [-80.0, 60.0, 10.0, -10.0, -10.0, 0.0])
    # a turn that would leave the bounds (−80° below −45°) is not made; the others are
    narrow = nearest_equivalent(q, np.zeros(6), robot, np.full(6, -np.pi / 4), upper)
    assert np.allclose(np.degrees(narrow), [280.0, 60.0, 10.0, -10.0, -10.0, 0.0])
