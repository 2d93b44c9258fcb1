"""The robot as a stick figure: the origin of every joint frame and the flange at given poses.

Pinocchio's forward kinematics of the chain the :class:`~doe_calib.model.robot.Robot`
describes (its nominal joint placements and axes, no URDF file needed), for
drawing the robot in each pose of a design.
"""
from __future__ import annotations

import numpy as np


def chain_model(robot):
    """A Pinocchio model of the robot's chain: one joint per joint, the flange as frame ``flange``.

    Examples
    --------
    >>> from doe_calib import Robot, examples
    >>> chain_model(Robot.from_urdf(examples.ROBOT_URDF)).nq
    6
    """
    import pinocchio as pin

    model = pin.Model()
    parent = 0
    for joint in robot.joints:
        axis = np.asarray(joint.axis, float)
        kind = (pin.JointModelRevoluteUnaligned if joint.kind == "revolute"
                else pin.JointModelPrismaticUnaligned)
        parent = model.addJoint(parent, kind(axis), pin.SE3(joint.placement_matrix), joint.name)
    flange = pin.SE3(np.array(robot.flange_placement, float).reshape(4, 4))
    model.addFrame(pin.Frame("flange", parent, 0, flange, pin.FrameType.OP_FRAME))
    return model


def chain_poses(robot, q):
    """Pinocchio's data of the robot's chain (:func:`chain_model`) at each pose of ``q``
    ((M, N), rad or m), with the flange frame's id: (data, flange) M times, one data reused."""
    import pinocchio as pin

    model = chain_model(robot)
    data = model.createData()
    flange = model.getFrameId("flange")
    for pose in np.atleast_2d(np.asarray(q, float)):
        pin.framesForwardKinematics(model, data, pose)
        yield data, flange


def skeleton_points(robot, q) -> np.ndarray:
    """Base origin, each joint frame's origin and the flange at each pose, robot base frame.

    Parameters
    ----------
    robot : Robot
    q : array_like, shape (M, N)
        Joint values, rad (m for prismatic joints).

    Returns
    -------
    ndarray, shape (M, N + 2, 3)
        Points in m, from the base to the flange.
    """
    return np.array([[np.zeros(3)] + [data.oMi[j].translation.copy()
                                      for j in range(1, len(data.oMi))]
                     + [data.oMf[flange].translation] for data, flange in chain_poses(robot, q)])
