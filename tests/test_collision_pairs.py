"""Pairs whose distance never changes (collision/pairs.py ``never_moving``) against every pair's
distance at every sample (pin.computeDistance on a GeometryData of its own)."""
import numpy as np
import pinocchio as pin

from doe_calib import Robot, Tool, examples
from doe_calib.collision import build_collision_model
from doe_calib.collision.pairs import CONSTANT, never_moving
from doe_calib.design.candidates.constraint_file import read_constraints


def test_never_moving_pairs_are_those_constant_over_every_sample():
    robot = Robot.from_urdf(examples.ROBOT_URDF)
    tool = Tool.from_yaml(examples.TOOL_YAML)
    cm = build_collision_model(robot, tool, constraints=read_constraints(
        examples.CELL_YAML, robot, tool), samples=40)
    rng = np.random.default_rng(4)
    lo = np.where(np.isfinite(robot.lower), robot.lower, -np.pi)
    hi = np.where(np.isfinite(robot.upper), robot.upper, np.pi)
    # a few samples differ from the others only in the last joint: pairs it does not move
    # are constant over those, and must still be judged on all
    q = rng.uniform(lo, hi, (30, robot.n_joints))
    q[:25] = q[0]
    q[:25, -1] = rng.uniform(lo[-1], hi[-1], 25)
    x = cm.configurations(q)
    data, gdata = cm.model.createData(), cm.geometry.createData()
    d = []
    for c in x.T:
        pin.updateGeometryPlacements(cm.model, data, cm.geometry, gdata, c)
        d.append([pin.computeDistance(cm.geometry, gdata, k).min_distance
                  for k in range(len(cm.geometry.collisionPairs))])
    d = np.array(d)
    truth = d.max(axis=0) - d.min(axis=0) < CONSTANT
    found = never_moving(cm.model, cm.geometry, x)
    assert np.array_equal(found, truth)
    assert truth.any() and not truth.all()
    # some pair is constant over the first 25 samples and moves after them
    assert ((d[:25].max(axis=0) - d[:25].min(axis=0) < CONSTANT) & ~truth).any()
