"""The skipping move check (collision/bounds.py, clearance.check_segment) against dense checks.

Truth here is Pinocchio/coal evaluated at every pose of the ≤ 1° grid: the collision test of
every pair at every pose (what check_segment did before it skipped), and each pair's distance
(pin.computeDistance) at every pose. The skipping check must find the same first pose and pair
as the first, and never pass a pose where the second finds a pair inside its margin.
"""
import math
from importlib import metadata
from pathlib import Path

import numpy as np
import pinocchio as pin
import pytest

from doe_calib import Robot, Tool, examples
from doe_calib.collision import SEGMENT_STEP, Workspace, build_collision_model, check_segment
from doe_calib.collision.bounds import body_radius, motion_weights
from doe_calib.design.candidates.constraint_file import read_constraints
from doe_calib.design.problem import LoadCase


def _ur5():
    try:
        files = metadata.distribution("example-robot-data").files or []
    except metadata.PackageNotFoundError:
        pytest.skip("the UR5 URDF needs `pip install example-robot-data`")
    for f in files:
        if str(f).endswith("robots/ur_description/urdf/ur5_robot.urdf"):
            return Path(f.locate()).resolve()
    pytest.skip("ur5_robot.urdf is not in example-robot-data")


@pytest.fixture(scope="module", params=["ur5", "kr270"])
def cell(request):
    """A collision model of a robot in its example cell, with its tool and a payload."""
    if request.param == "ur5":
        robot = Robot.from_urdf(_ur5())
        tool, where, load = Tool.from_yaml(examples.UR_TOOL_YAML), examples.UR5_CELL_YAML, \
            LoadCase(3.0, (0.0, 0.0, 0.08), radius=0.04)
    else:
        robot = Robot.from_urdf(examples.ROBOT_URDF)
        tool, where, load = Tool.from_yaml(examples.TOOL_YAML), examples.CELL_YAML, \
            LoadCase(250.0, (0.0, 0.0, 0.2), radius=0.1)
    constraints = read_constraints(where, robot, tool)
    return robot, build_collision_model(robot, tool, (load,), constraints, samples=100)


def _limits(robot):
    lo = np.where(np.isfinite(robot.lower), robot.lower, -np.pi)
    hi = np.where(np.isfinite(robot.upper), robot.upper, np.pi)
    return lo, hi


def _distances(cm, q):
    """Every checked pair's distance (m) at each pose of q (M, N), from a fresh GeometryData."""
    data, gdata = cm.model.createData(), cm.geometry.createData()
    out = []
    for x in cm.configurations(q).T:
        pin.updateGeometryPlacements(cm.model, data, cm.geometry, gdata, x)
        out.append([pin.computeDistance(cm.geometry, gdata, k).min_distance
                    for k in range(len(cm.geometry.collisionPairs))])
    return np.array(out)


def _dense(cm, qa, qb, margins):
    """First (pose, pair) of the ≤ 1° grid some pair's collision test flags: every pair tested."""
    data, gdata = cm.model.createData(), cm.geometry.createData()
    for request, m in zip(gdata.collisionRequests, margins):
        request.security_margin = m
    n = max(2, int(np.ceil(np.max(np.abs(qb - qa)) / SEGMENT_STEP)) + 1)
    t = np.linspace(0.0, 1.0, n)
    for i, x in enumerate(cm.configurations(qa + t[:, None] * (qb - qa)).T):
        pin.computeCollisions(cm.model, data, cm.geometry, gdata, x, False)
        hit = [k for k, r in enumerate(gdata.collisionResults) if r.isCollision()]
        if hit:
            return n, float(t[i]), cm.pair_name(hit[0])
    return n, None, None


def test_every_body_is_inside_its_bounding_sphere(cell):
    _, cm = cell
    for g in cm.geometry.geometryObjects:
        if hasattr(g.geometry, "vertices"):
            points = np.asarray(g.geometry.vertices()) @ g.placement.rotation.T \
                + g.placement.translation
            assert np.linalg.norm(points, axis=1).max() <= body_radius(g) + 1e-12, g.name


def test_no_pair_closes_faster_than_its_weights(cell):
    """Over random 5° moves, each pair's distance changes by at most W @ |Δq|."""
    robot, cm = cell
    weights = motion_weights(cm.model, cm.geometry, cm.joint_names)
    assert weights.shape == (len(cm.geometry.collisionPairs), robot.n_joints)
    rng = np.random.default_rng(3)
    lo, hi = _limits(robot)
    qa = rng.uniform(lo, hi, (40, robot.n_joints))
    qb = qa + rng.uniform(-1, 1, qa.shape) * math.radians(5)
    da, db = _distances(cm, qa), _distances(cm, qb)
    bound = np.abs(qb - qa) @ weights.T
    apart = (da > 0) & (db > 0)  # penetration depths are not distances
    assert (np.abs(db - da)[apart] <= bound[apart] + 1e-9).all()
    # the bound is not vacuous: it is within a factor of 100 of the largest change seen
    assert np.median(bound[apart]) < 100 * np.abs(db - da)[apart].max()


def test_a_pair_the_chain_carries_rigidly_gets_no_weight(cell):
    """The marker spheres and rods sit on the flange's link: their pairs never move."""
    _, cm = cell
    weights = motion_weights(cm.model, cm.geometry, cm.joint_names)
    objects = cm.geometry.geometryObjects
    for k, pair in enumerate(cm.geometry.collisionPairs):
        a, b = objects[pair.first].parentJoint, objects[pair.second].parentJoint
        if a == b:
            assert not weights[k].any()
        if min(a, b) == 0:  # a body on the base: every joint up to the other one moves it
            assert (weights[k, :max(a, b)] > 0).all() and not weights[k, max(a, b):].any()


def test_no_bound_without_every_joint():
    robot = Robot.from_urdf(examples.ROBOT_URDF)
    cm = build_collision_model(robot, Tool.from_yaml(examples.TOOL_YAML), samples=20)
    assert motion_weights(cm.model, cm.geometry, cm.joint_names[:-1]) is None


@pytest.mark.parametrize("margin", [None, 0.0, 0.05])
def test_skipping_check_finds_what_the_dense_one_finds(cell, margin):
    """Random moves, many of them grazing: the same first pose and pair, never a miss."""
    robot, cm = cell
    rng = np.random.default_rng(11)
    lo, hi = _limits(robot)
    margins = np.broadcast_to(np.asarray(cm.move_margins if margin is None else margin, float),
                              len(cm.margins))
    ws = Workspace(cm)
    found = grazing = 0
    for _ in range(8):
        qa, qb = rng.uniform(lo, hi, (2, robot.n_joints))
        qb = qa + (qb - qa) * rng.uniform(0.05, 0.6)
        n, first, pair = _dense(cm, qa, qb, margins)
        moves = [(qa, qb)]
        if first is not None and first > 0:
            # a move stopping just short of the first pose flagged: its end grazes the margin
            moves.append((qa, qa + (first - 0.5 / (n - 1)) * (qb - qa)))
        for a, b in moves:
            fast = check_segment(cm, a, b, margins, workspace=ws)
            dense = _dense(cm, a, b, margins)
            assert (fast.samples, fast.first, fast.pair) == dense
            found += fast.first is not None
            m = max(2, int(np.ceil(np.max(np.abs(b - a)) / SEGMENT_STEP)) + 1)
            t = np.linspace(0.0, 1.0, m)
            d = _distances(cm, a + t[:, None] * (b - a)) - margins
            inside = np.flatnonzero((d < -1e-6).any(axis=1))
            if len(inside):
                assert fast.first is not None and fast.first <= t[inside[0]]
            grazing += bool((np.abs(d) < 0.005).any())
    assert found >= 3 and grazing >= 3  # the moves did test near contact


@pytest.mark.parametrize("margin", [0.0, 0.0025, 0.01, 0.05])
def test_coal_bound_is_on_the_distance_less_the_margin(cell, margin):
    """The skip's premise: with a security margin m, coal's ``distance_lower_bound`` of a pair
    it finds clear is at most its distance less m (exactly that for a sphere and a box: the
    margin is taken off once)."""
    robot, cm = cell
    rng = np.random.default_rng(5)
    lo, hi = _limits(robot)
    q = rng.uniform(lo, hi, (25, robot.n_joints))
    d = _distances(cm, q)
    ws = Workspace(cm)
    ws.set_margins([margin] * len(cm.margins))
    kind = [type(g.geometry).__name__ for g in cm.geometry.geometryObjects]
    exact = [{kind[p.first], kind[p.second]} == {"Sphere", "Box"}
             for p in cm.geometry.collisionPairs]
    clear = near = exactly = 0
    for x, row in zip(cm.configurations(q).T, d):
        pin.updateGeometryPlacements(cm.model, ws.data, cm.geometry, ws.geometry, x)
        for k in range(len(row)):
            if pin.computeCollision(cm.geometry, ws.geometry, k):
                assert row[k] < margin + 1e-6
                continue
            bound = ws.results[k].distance_lower_bound
            assert bound <= row[k] - margin + 1e-9
            clear += 1
            if exact[k]:
                assert bound == pytest.approx(row[k] - margin, abs=1e-9)
                exactly += 1
            near += row[k] - margin < 0.05
    assert clear > 1000 and near > 10 and exactly > 50


def test_a_move_that_ends_touching_is_found_as_the_dense_check_finds_it(cell):
    """Moves ending one step short of, at, and one step past their first pose inside the margin:
    the dense check's answers, and the distances (every pair, every pose) agree."""
    robot, cm = cell
    rng = np.random.default_rng(17)
    lo, hi = _limits(robot)
    margins = np.asarray(cm.move_margins, float)
    ws, built = Workspace(cm), 0
    while built < 3:
        qa, qb = rng.uniform(lo, hi, (2, robot.n_joints))
        qb = qa + 0.3 * (qb - qa)
        n, at, _ = _dense(cm, qa, qb, margins)
        t = np.linspace(0.0, 1.0, n)
        if at is None or at < 3 * t[1]:
            continue  # free, or flagged at its start
        first = int(round(at * (n - 1)))
        ends = [qa + t[end] * (qb - qa) for end in (first - 1, first, first + 1)]
        if (np.abs(_distances(cm, np.array(ends)) - margins) < 1e-6).any():
            continue  # too close to call at an end
        built += 1
        for b, expect_free in zip(ends, (True, False, False)):
            fast = check_segment(cm, qa, b, margins, workspace=ws)
            assert (fast.samples, fast.first, fast.pair) == _dense(cm, qa, b, margins)
            assert fast.free == expect_free
        # the move ending at its first pose inside: only its end is inside, by the distances
        m = check_segment(cm, qa, ends[1], margins, workspace=ws).samples
        tt = np.linspace(0.0, 1.0, m)
        inside = (_distances(cm, qa + tt[:, None] * (ends[1] - qa)) < margins).any(axis=1)
        assert inside[-1] and not inside[:-1].any()


def test_a_move_checked_again_with_other_margins_or_step_is_the_dense_check(cell):
    """One workspace checks a move with other margins and steps: each check is the dense one."""
    robot, cm = cell
    rng = np.random.default_rng(23)
    lo, hi = _limits(robot)
    qa, qb = rng.uniform(lo, hi, (2, robot.n_joints))
    ws, dense = Workspace(cm), Workspace(cm, bounded=False)
    first = check_segment(cm, qa, qb, cm.move_margins, workspace=ws)
    assert first == check_segment(cm, qa, qb, cm.move_margins, workspace=dense)
    for margin, step in ((0.0, SEGMENT_STEP), (0.3, SEGMENT_STEP), (None, 2 * SEGMENT_STEP)):
        again = check_segment(cm, qa, qb, margin, step, workspace=ws)
        margins = np.broadcast_to(np.asarray(cm.margins if margin is None else margin, float),
                                  len(cm.margins))
        n, at, pair = _dense(cm, qa, qb, margins) if step == SEGMENT_STEP else \
            (again.samples, again.first, again.pair)
        assert (again.samples, again.first, again.pair) == (n, at, pair)
    assert check_segment(cm, qa, qb, 0.3, workspace=ws).pair is not None  # 30 cm: touching


def test_poses_screened_in_shares_are_screened_as_one(cell, monkeypatch):
    """The candidates' screening split among forked processes keeps and counts the poses as
    one process screening them all does."""
    from doe_calib.design.candidates import draw

    robot, cm = cell
    lo, hi = _limits(robot)
    q = np.random.default_rng(37).uniform(lo, hi, (600, robot.n_joints))
    ok = np.random.default_rng(38).random(len(q)) < 0.9
    monkeypatch.setattr(draw, "_SHARE", 10**6)
    one, one_masks = draw.screen_collisions(cm, q, ok, Workspace(cm))
    monkeypatch.setattr(draw, "_SHARE", 70)
    many, many_masks = draw.screen_collisions(cm, q, ok, Workspace(cm))
    assert one.any() and (~one & ok).any()
    assert np.array_equal(one, many) and list(one_masks) == list(many_masks)
    assert all(np.array_equal(one_masks[k], many_masks[k]) for k in one_masks)
