"""A Function mapped over M configurations equals its evaluation one configuration at a time."""
import numpy as np

from doe_calib import Configurations, build_model, examples
from doe_calib.model.evaluation import Workspace, evaluate
from doe_calib.model.robot import Robot
from doe_calib.model.simulate import random_configurations, random_truth
from doe_calib.model.tool import Tool


def test_shared_and_per_configuration_inputs_equal_single_calls():
    robot, tool = Robot.from_urdf(examples.ROBOT_URDF), Tool.from_yaml(examples.TOOL_YAML)
    model = build_model(robot, tool, "joint_offset+joint_compliance")
    rng = np.random.default_rng(8)
    q = random_configurations(robot, 37, rng)
    cfg = Configurations.from_arrays(q, rng.normal(size=(37, 6)) * ([900.0] * 3 + [0.0] * 3))
    values = random_truth(model, rng)
    point = np.array([0.1, -0.05, 0.2])  # a 1-D extra input: shared by every configuration
    ws = Workspace()
    x, jac = evaluate(model.point_robot, cfg, values, point, workspace=ws)
    for i in (0, 17, 36):
        one = Configurations.from_arrays(q[i:i + 1], cfg.wrench[i:i + 1])
        xi, ji = evaluate(model.point_robot, one, values, point, workspace=Workspace())
        np.testing.assert_array_equal(x[i], xi[0])
        np.testing.assert_array_equal(jac[i], ji[0])
    # new shared values reach every configuration; the same values again give the same bits
    moved = evaluate(model.point_robot, cfg, values, point + 0.01, workspace=ws)[0]
    assert np.all(np.abs(moved - x).max(axis=(1, 2)) > 1e-4)
    again = evaluate(model.point_robot, cfg, values, point, workspace=ws)[0]
    np.testing.assert_array_equal(again, x)
