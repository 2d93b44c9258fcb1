"""The convex-hull pre-check (collision/hulls.py) against the meshes' own collision tests.

Truth here is the test of every pair's meshes in checking order (``Workspace(cm, hulls=False)``,
what the screening did before): with hulls, every pose must get the same first pair, at the
poses' margins, at the moves' and at zero, and a planned move the same path.
"""
import numpy as np
import pinocchio as pin
import pytest
from test_collision_bounds import _ur5

from doe_calib import Robot, Tool, examples
from doe_calib.collision import (PlannerSettings, Workspace, build_collision_model,
                                 check_segment, plan_move, too_close)
from doe_calib.collision.hulls import HULL_SLACK, convex_hulls
from doe_calib.design.candidates.constraint_file import read_constraints
from doe_calib.design.problem import LoadCase


def _ur5_cell():
    robot, tool = Robot.from_urdf(_ur5()), Tool.from_yaml(examples.UR_TOOL_YAML)
    constraints = read_constraints(examples.UR5_CELL_YAML, robot, tool)
    cm = build_collision_model(robot, tool, (LoadCase(3.0, (0.0, 0.0, 0.08), radius=0.04),),
                               constraints)
    return robot, constraints.bounds(robot), cm


@pytest.fixture(scope="module", params=["ur5", "kr270"])
def cell(request):
    """(robot, joint bounds, collision model): the UR5 in its cell with 3 kg (meshes), the
    KR 270 with its tool (primitives only)."""
    if request.param == "ur5":
        return _ur5_cell()
    robot, tool = Robot.from_urdf(examples.ROBOT_URDF), Tool.from_yaml(examples.TOOL_YAML)
    lo = np.where(np.isfinite(robot.lower), robot.lower, -np.pi)
    hi = np.where(np.isfinite(robot.upper), robot.upper, np.pi)
    return robot, (lo, hi), build_collision_model(robot, tool)


def test_hulls_replace_the_meshes_only(cell):
    robot, _, cm = cell
    if cm.hulls is None:  # the KR 270's links are boxes and cylinders: nothing to pre-check
        assert not any(type(o.geometry).__name__.startswith("BVH")
                       for o in cm.geometry.geometryObjects)
        return
    assert [(p.first, p.second) for p in cm.hulls.collisionPairs] == \
        [(p.first, p.second) for p in cm.geometry.collisionPairs]
    for mesh, hull in zip(cm.geometry.geometryObjects, cm.hulls.geometryObjects):
        assert (hull.name, hull.parentJoint) == (mesh.name, mesh.parentJoint)
        assert np.allclose(hull.placement.homogeneous, mesh.placement.homogeneous)
        if type(mesh.geometry).__name__.startswith("BVH"):
            assert type(hull.geometry).__name__ == "Convex"
        else:
            assert type(hull.geometry) is type(mesh.geometry)


def test_hull_distance_is_below_the_mesh_distance(cell):
    robot, (lo, hi), cm = cell
    if cm.hulls is None:
        pytest.skip("no mesh")
    rng = np.random.default_rng(5)
    data, mdata, hdata = cm.model.createData(), cm.geometry.createData(), cm.hulls.createData()
    for x in cm.configurations(rng.uniform(lo, hi, (30, robot.n_joints))).T:
        pin.updateGeometryPlacements(cm.model, data, cm.geometry, mdata, x)
        pin.updateGeometryPlacements(cm.model, data, cm.hulls, hdata, x)
        for k in range(len(cm.geometry.collisionPairs)):
            mesh = pin.computeDistance(cm.geometry, mdata, k).min_distance
            hull = pin.computeDistance(cm.hulls, hdata, k).min_distance
            if mesh > 0:  # within coal's tolerances (GJK: 1e-6 of the distance), far below
                assert hull <= mesh + HULL_SLACK / 100, cm.pair_name(k)


@pytest.mark.parametrize("which", ["pose", "move", "zero"])
def test_too_close_with_hulls_is_the_mesh_answer_pose_by_pose(cell, which):
    robot, (lo, hi), cm = cell
    margin = {"pose": None, "move": cm.move_margins, "zero": 0.0}[which]
    rng = np.random.default_rng(11)
    q = rng.uniform(lo, hi, (4000, robot.n_joints))
    ws = Workspace(cm)
    reference = too_close(cm, q, margin, Workspace(cm, hulls=False))
    assert (too_close(cm, q, margin, ws) == reference).all()
    assert 0.1 < (reference < 0).mean() < 0.9  # both free and hit poses are compared
    if ws.hulls is None:
        return
    assert all(ws.hulls.activeCollisionPairs)  # the pairs deactivated on the way are back
    # the hulls flag pairs the meshes clear: the search goes on past them
    hdata = cm.hulls.createData()
    for request, m in zip(hdata.collisionRequests, np.broadcast_to(
            np.asarray(cm.margins if margin is None else margin, float), len(ws.hull_results))):
        request.security_margin = m + HULL_SLACK
    flagged = [pin.computeCollisions(cm.model, cm.model.createData(), cm.hulls, hdata, x, True)
               for x in cm.configurations(q[reference < 0][:500]).T]
    assert any(flagged)


def test_a_workspace_moved_between_margins_answers_as_a_fresh_one(cell):
    robot, (lo, hi), cm = cell
    q = np.random.default_rng(2).uniform(lo, hi, (300, robot.n_joints))
    ws = Workspace(cm)
    first = too_close(cm, q, 0.0, ws)
    too_close(cm, q, workspace=ws)
    assert (too_close(cm, q, 0.0, ws) == first).all()
    assert (first == too_close(cm, q, 0.0, Workspace(cm, hulls=False))).all()


@pytest.mark.parametrize("which", ["pose", "move", "zero"])
def test_a_move_checked_with_hulls_is_the_dense_mesh_check(cell, which):
    """Skipping by the hulls' bounds finds the first pose and pair of every pair's meshes tested
    at every pose, also on moves that end just short of it, and on the pairs found alone."""
    robot, (lo, hi), cm = cell
    if cm.hulls is None:
        pytest.skip("no mesh: moves are checked as before")
    margin = {"pose": None, "move": cm.move_margins, "zero": 0.0}[which]
    rng = np.random.default_rng(7)
    ws, dense = Workspace(cm), Workspace(cm, bounded=False, hulls=False)
    starts = rng.uniform(lo, hi, (300, robot.n_joints))
    starts = starts[too_close(cm, starts, margin, dense) < 0][:30]
    found = 0
    for qa in starts:
        qb = qa + (rng.uniform(lo, hi) - qa) * rng.uniform(0.05, 0.5)
        check = check_segment(cm, qa, qb, margin, workspace=ws)
        assert check == check_segment(cm, qa, qb, margin, workspace=dense)
        if check.free or check.first == 0:
            continue
        found += 1
        short = qa + (check.first - 0.5 / (check.samples - 1)) * (qb - qa)  # grazes the margin
        assert check_segment(cm, qa, short, margin, workspace=ws) == \
            check_segment(cm, qa, short, margin, workspace=dense)
        pairs = [cm.pairs.index(check.pair), 0]
        assert check_segment(cm, qa, qb, margin, workspace=ws, pairs=pairs) == \
            check_segment(cm, qa, qb, margin, workspace=dense, pairs=pairs)
    assert found >= 5


def test_a_planned_move_is_the_path_planned_on_the_meshes():
    _, _, cm = _ur5_cell()
    settings = PlannerSettings(checks=1500)
    for a, b in (([62.1, 243.9, 81.1, -96.9, -37.1, -95.0],
                  [338.7, 197.2, 104.2, 186.2, 69.6, 299.9]),
                 ([333.8, -70.6, -73.3, 249.1, -269.6, 167.7],
                  [-224.1, -77.2, -96.0, 245.0, -78.9, 340.8])):
        a, b = np.radians(a), np.radians(b)  # free poses; their straight move collides
        assert not check_segment(cm, a, b, cm.move_margins).free
        hulls = plan_move(cm, a, b, settings=settings, workspace=Workspace(cm))
        meshes = plan_move(cm, a, b, settings=settings, workspace=Workspace(cm, hulls=False))
        assert hulls is not None and meshes is not None and len(hulls.via)
        assert hulls.samples == meshes.samples
        np.testing.assert_array_equal(np.array(hulls.via), np.array(meshes.via))


def test_a_flat_mesh_keeps_its_mesh_and_a_model_of_flat_meshes_gets_no_hulls():
    """Qhull cannot build the hull of a plate (it crashes on coplanar points): no hull."""
    import coal

    def mesh(corners):
        m = coal.BVHModelOBBRSS()
        m.beginModel(len(corners) - 2, len(corners))
        for i in range(1, len(corners) - 1):
            m.addTriangle(*(np.asarray(corners[j], float) for j in (0, i, i + 1)))
        m.endModel()
        return m

    plate = mesh([(0, 0, 0), (1, 0, 0), (1, 1, 0), (0, 1, 0)])
    solid = mesh([(0, 0, 0), (1, 0, 0), (0, 1, 0), (0, 0, 1)])
    geometry = pin.GeometryModel()
    for name, shape in (("plate", plate), ("solid", solid), ("ball", coal.Sphere(0.1))):
        geometry.addGeometryObject(pin.GeometryObject(name, 0, 0, pin.SE3.Identity(), shape))
    for a, b in ((0, 1), (0, 2), (1, 2)):
        geometry.addCollisionPair(pin.CollisionPair(a, b))
    hulls = convex_hulls(geometry)
    assert [type(o.geometry).__name__ for o in hulls.geometryObjects] == \
        ["BVHModelOBBRSS", "Convex", "Sphere"]
    assert len(hulls.collisionPairs) == 3
    geometry.removeGeometryObject("solid")
    assert convex_hulls(geometry) is None
