"""The tracker's beams (collision/beams.py) against coal's test of every beam and body, pose by
pose, in the UR5 and KR270 example cells; its numpy forward kinematics against Pinocchio's."""
import numpy as np
import pinocchio as pin

from doe_calib.collision import Workspace, blocked_beams, screen_beams
from doe_calib.collision.beams import _GAP, BEAM_RADIUS, _chain, _joint_frames, _sight
from doe_calib.collision.shapes import frame_along

from test_collision_bounds import _limits, cell  # noqa: F401  (its fixture, both cells)


def _beams_one_by_one(cm, q):
    """Per pose of q (M, N), (marker, first body) of each blocked beam: coal's test of every
    beam against every body it is checked against, pose by pose."""
    import coal

    data, gdata, objects = cm.model.createData(), cm.geometry.createData(), \
        cm.geometry.geometryObjects
    tracker, out, markers = np.asarray(cm.tracker), [], _sight(cm).markers
    for x in cm.configurations(q).T:
        pin.updateGeometryPlacements(cm.model, data, cm.geometry, gdata, x)
        found = []
        for marker, i, others in markers:
            line = gdata.oMg[i].translation - tracker
            length = np.linalg.norm(line) - objects[i].geometry.radius - BEAM_RADIUS - _GAP
            frame = frame_along(tracker + line / np.linalg.norm(line) * length / 2, line)
            for k in others if length > 0 else ():
                at = gdata.oMg[k]
                if coal.collide(coal.Capsule(BEAM_RADIUS, length),
                                coal.Transform3s(frame[:3, :3], frame[:3, 3]),
                                objects[k].geometry, coal.Transform3s(at.rotation, at.translation),
                                coal.CollisionRequest(), coal.CollisionResult()):
                    found.append((marker, cm.names[k]))
                    break
        out.append(tuple(found))
    return out


def test_beams_screened_at_once_are_those_coal_finds_pose_by_pose(cell):  # noqa: F811
    """The batched beam screening (numpy bounds, coal near contact) blocks the same beams by
    the same first bodies as coal's test of every beam and body at each of 3000 poses."""
    robot, cm = cell
    lo, hi = _limits(robot)
    q = np.random.default_rng(31).uniform(lo, hi, (3000, robot.n_joints))
    truth = _beams_one_by_one(cm, q)
    ws = Workspace(cm)
    assert [(b.marker, b.body) if b else None for b in screen_beams(cm, q, ws)] == \
        [found[0] if found else None for found in truth]
    assert 300 < sum(map(bool, truth)) < 2700  # both kinds of pose are tested
    assert sum(len(found) > 1 for found in truth) > 10  # and poses with beams blocked
    for x, found in zip(q[:200], truth):
        assert tuple((b.marker, b.body) for b in blocked_beams(cm, x, ws)) == found


def test_numpy_forward_kinematics_places_the_joints_as_pinocchio(cell):  # noqa: F811
    robot, cm = cell
    lo, hi = _limits(robot)
    q = np.random.default_rng(5).uniform(lo, hi, (50, robot.n_joints))
    frames = _joint_frames(_chain(cm), q)
    data = cm.model.createData()
    for x, placed in zip(cm.configurations(q).T, frames):
        pin.forwardKinematics(cm.model, data, x)
        assert np.abs(np.array([m.homogeneous for m in data.oMi]) - placed).max() < 1e-12


def test_numpy_forward_kinematics_of_every_joint_kind():
    """Revolute and prismatic joints, about any axis, and continuous ones, placed anywhere."""
    from types import SimpleNamespace

    from doe_calib.collision.model import pinocchio_configurations

    rng = np.random.default_rng(8)
    model = pin.Model()
    kinds = (pin.JointModelRZ(), pin.JointModelPX(), pin.JointModelRevoluteUnaligned(
        *(rng.normal(size=3) / np.sqrt(3))), pin.JointModelRUBY(),
        pin.JointModelPrismaticUnaligned(*(rng.normal(size=3) / np.sqrt(3))))
    parent = 0
    for k, kind in enumerate(kinds):
        parent = model.addJoint(parent, kind, pin.SE3.Random(), f"j{k}")
    names = tuple(model.names[1:])
    q = rng.uniform(-3, 3, (20, len(names)))
    frames = _joint_frames(_chain(SimpleNamespace(model=model, joint_names=names)), q)
    data = model.createData()
    for x, placed in zip(pinocchio_configurations(model, names, q).T, frames):
        pin.forwardKinematics(model, data, x)
        assert np.abs(np.array([m.homogeneous for m in data.oMi]) - placed).max() < 1e-12
