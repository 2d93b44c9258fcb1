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


def test_contact_rates_on_the_hulls_first_are_the_meshes_rates():
    """The UR5 cell's shares of random configurations with each pair too close, tested on the
    hulls first, are those of every pair's mesh test."""
    from test_collision_bounds import _limits, _ur5

    from doe_calib.collision.pairs import contact_rates
    from doe_calib.design.problem import LoadCase

    robot, tool = Robot.from_urdf(_ur5()), Tool.from_yaml(examples.UR_TOOL_YAML)
    cm = build_collision_model(robot, tool, (LoadCase(3.0, (0.0, 0.0, 0.08), radius=0.04),),
                               read_constraints(examples.UR5_CELL_YAML, robot, tool), samples=20)
    lo, hi = _limits(robot)
    x = cm.configurations(np.random.default_rng(6).uniform(lo, hi, (300, robot.n_joints)))
    margins = 3 * np.asarray(cm.margins)  # more pairs too close, some of them sometimes
    skipped = {0, 5}
    data, gdata = cm.model.createData(), cm.geometry.createData()
    for request, m in zip(gdata.collisionRequests, margins):
        request.security_margin = m
    hits = []
    for c in x.T:
        pin.computeCollisions(cm.model, data, cm.geometry, gdata, c, False)
        hits.append([r.isCollision() for r in gdata.collisionResults])
    truth = np.mean(hits, axis=0)
    truth[list(skipped)] = 0
    assert cm.hulls is not None and ((truth > 0) & (truth < 1)).sum() > 5
    rates = contact_rates(cm.model, cm.geometry, x, margins, skipped, cm.hulls)
    assert np.array_equal(rates, truth)
