"""The CasADi chain against Pinocchio's own forward kinematics, at zero errors."""
from pathlib import Path

import numpy as np
import pinocchio as pin
import pytest

from doe_calib import Configurations, Robot, examples
from doe_calib.model.evaluation import evaluate
from doe_calib.model.simulate import random_configurations

ODD_CHAIN_URDF = Path(__file__).parent / "data" / "odd_chain.urdf"


def _pinocchio_flange(urdf, flange, robot, q_chain):
    model = pin.buildModelFromUrdf(str(urdf))
    data = model.createData()
    fid = model.getFrameId(flange)
    out = []
    for qc in q_chain:
        q = pin.neutral(model)
        for name, value in zip(robot.joint_names, qc):
            jm = model.joints[model.getJointId(name)]
            if jm.nq == 2:  # continuous joint: (cos, sin)
                q[jm.idx_q:jm.idx_q + 2] = np.cos(value), np.sin(value)
            else:
                q[jm.idx_q] = value
        pin.framesForwardKinematics(model, data, q)
        out.append(data.oMf[fid].homogeneous.copy())
    return np.array(out)


@pytest.mark.parametrize("urdf, flange", [(examples.ROBOT_URDF, "tool0"),
                                          (examples.THREE_DOF_URDF, "flange"),
                                          (ODD_CHAIN_URDF, "tip")])
def test_flange_pose_matches_pinocchio(urdf, flange, rng):
    from doe_calib import Tool, build_model

    robot = Robot.from_urdf(urdf, flange=flange)
    tool = Tool.from_markers({"A": [0, 0, 100], "B": [100, 0, 0], "C": [0, 100, 0]})
    model = build_model(robot, tool, "joint_offset+geometry+joint_compliance")
    q = random_configurations(robot, 50, rng, margin=0.0)
    cfg = Configurations.from_arrays(q, wrench=rng.normal(size=(50, 6)) * 100)
    values = model.nominal().values  # zero errors, identity base, compliances 0
    rot, trans = evaluate(model.flange, cfg, values)
    ref = _pinocchio_flange(urdf, flange, robot, q)
    assert np.abs(trans[:, :, 0] - ref[:, :3, 3]).max() < 1e-9
    assert np.abs(rot - ref[:, :3, :3]).max() < 1e-9


def test_default_flange_is_last_link():
    assert Robot.from_urdf(examples.ROBOT_URDF).flange == "tool0"
    assert Robot.from_urdf(ODD_CHAIN_URDF).flange == "tip"


def test_chain_reads_joint_kinds_and_limits():
    robot = Robot.from_urdf(ODD_CHAIN_URDF)
    assert [j.kind for j in robot.joints] == ["prismatic", "revolute", "revolute", "revolute"]
    assert robot.joints[0].upper == pytest.approx(0.35)
    assert np.isinf(robot.joints[2].upper)  # continuous
    assert np.allclose(robot.joints[1].axis, [0.6, 0, 0.8])


def test_tiago_arm_chain_matches_pinocchio(rng):
    """A real robot description (example-robot-data, a test dependency)."""
    from studies.tiago_mocap import tiago_urdf

    urdf = tiago_urdf()
    if urdf is None:
        pytest.skip("TIAGo URDF not available: pip install example-robot-data")
    robot = Robot.from_urdf(urdf, flange="arm_7_link")
    assert robot.joint_names[0] == "torso_lift_joint" and robot.n_joints == 8
