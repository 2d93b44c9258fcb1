"""A flange half a turn off its target orientation is not reached: sin θ · axis is 0 at π."""
import re
import warnings

import casadi as ca
import numpy as np
import pinocchio as pin
import pytest
from scipy.spatial.transform import Rotation

from doe_calib import Configurations, IdentificationResult, Robot, Tool, build_model, examples
from doe_calib.compensation import Targets, compensate
from doe_calib.compensation.nlp import orientation_equations, rotation_error
from doe_calib.errors import ConvergenceWarning

#: Wrist limits (rad) narrow enough that neither a6 nor a wrist flip (a4 + π, −a5) can turn
#: the flange half a turn about its z axis (the axis of a6).
WRIST = 0.5
TCP = np.array([0.0, 0.0, 0.2])   # on the flange z axis: a6 does not move it


def _narrow_wrist(path):
    urdf = open(examples.ROBOT_URDF).read()
    for joint in ("a4", "a6"):
        urdf = re.sub(rf'(<joint name="{joint}".*?<limit lower=")[^"]*(" upper=")[^"]*"',
                      rf'\g<1>{-WRIST}\g<2>{WRIST}"', urdf, flags=re.S)
    path.write_text(urdf)
    return path


def _flange_rotations(path, q):
    """The flange orientation of each row of ``q`` by Pinocchio's FK of the URDF (no limits)."""
    pm = pin.buildModelFromUrdf(str(path))
    data, frame = pm.createData(), pm.getFrameId("tool0")
    out = []
    for qi in q:
        pin.framesForwardKinematics(pm, data, qi)
        out.append(data.oMf[frame].rotation.copy())
    return np.array(out)


def test_half_a_turn_is_named_not_reached(tmp_path):
    path = _narrow_wrist(tmp_path / "narrow.urdf")
    robot, tool = Robot.from_urdf(path), Tool.from_yaml(examples.TOOL_YAML)
    assert robot.upper[3] == robot.upper[5] == WRIST
    model = build_model(robot, tool, "joint_offset")
    params = model.nominal().updated(base_x=1.5, base_y=-1.2, base_z=0.3, base_rx=0.4,
                                     base_ry=-0.2, base_rz=1.1)
    n = int(params.free.sum())
    result = IdentificationResult(robot, tool, model.spec, "point", params, np.eye(n) * 1e-12,
                                  1.0, {"rms_mm": 0.0}, {}, 30, 0.02)
    # row "ok" is inside the limits; row "turned" asks a6 half a turn beyond its limit, where
    # the solver starts (the programmed q clipped): same TCP position, flange turned by π
    q = np.array([[0.3, -1.2, 1.0, 0.2, 0.7, 0.1],
                  [0.3, -1.2, 1.0, 0.2, 0.7, WRIST + np.pi]])
    targets = Targets(Configurations.from_arrays(q, pose=["ok", "turned"]))
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        out = compensate(model, result, targets, TCP)
    # the angle from the target orientation of each returned q′, by Pinocchio and scipy
    r_target, r_got = _flange_rotations(path, q), _flange_rotations(path, out.q_compensated)
    angle = np.degrees([Rotation.from_matrix(a.T @ b).magnitude()
                        for a, b in zip(r_target, r_got)])
    assert angle[0] < 1e-6 and out.converged[0] and out.note[0] == ""
    assert angle[1] > 1.0               # the limits keep the flange off its target
    assert not out.converged[1]
    stated = re.search(r"target not reached: off by [^,]* mm, ([0-9.]+) deg", out.note[1])
    assert stated, out.note[1]
    assert abs(float(stated.group(1)) - angle[1]) <= 0.5   # printed to 3 digits
    assert abs(np.degrees(out.rotation_residual[1]) - angle[1]) < 1e-6
    assert any(issubclass(w.category, ConvergenceWarning) and "turned (" in str(w.message)
               for w in caught)


def test_orientation_equations_vanish_at_the_target_only():
    """vee (sin θ · axis) is ~0 near θ = π; g grows there as tan(θ/2); below 90° g is vee."""
    r_t, r = ca.SX.sym("R_t", 3, 3), ca.SX.sym("R", 3, 3)
    f = ca.Function("f", [r_t, r], [orientation_equations(r_t, r), rotation_error(r_t, r)])
    axis = np.array([0.3, -0.5, 0.8]) / np.linalg.norm([0.3, -0.5, 0.8])
    r_target = Rotation.from_rotvec([0.2, 1.0, -0.4]).as_matrix()
    for deg in (1e-6, 30.0, 89.0, 91.0, 150.0, 179.999):
        turned = r_target @ Rotation.from_rotvec(np.radians(deg) * axis).as_matrix()
        g, vee = (np.asarray(v).ravel() for v in f(r_target, turned))
        theta = np.radians(deg)
        assert np.linalg.norm(vee) == pytest.approx(np.sin(theta), rel=1e-6)
        expected = np.sin(theta) if deg <= 90 else np.tan(theta / 2)
        assert g == pytest.approx(expected * axis, rel=1e-6)
        if deg <= 90:
            assert np.array_equal(g, vee)
