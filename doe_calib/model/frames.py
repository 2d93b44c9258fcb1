"""Frames a cell file or a targets file may be written in, as placements in the robot base frame.

The robot base frame of doe_calib is the URDF's root (Pinocchio's universe):
what ``base_link`` is on most URDFs. A file may instead name

* any frame of the URDF that does not move with the joints (a link or a fixed
  joint: ``base``, ``world``, ``table``), placed as Pinocchio places it at
  the neutral configuration;
* ``base_link`` or ``base`` on a URDF that lacks them: the root, and the root
  turned 180° about z (the Universal Robots controller's ``base`` frame, which
  UR's own URDFs declare as a link of that name).

``tracker`` (the laser tracker's frame) is known only with an identification
result, and is resolved where the result is (compensation targets).
"""
from __future__ import annotations

from pathlib import Path

import numpy as np

from doe_calib.errors import ModelError

#: The frame a file is in when it names none.
DEFAULT_FRAME = "base_link"
#: Frames with a fixed meaning when the URDF has no frame of that name (4×4, in the root).
CONVENTIONS = {
    "base_link": np.eye(4),
    "base": np.diag([-1.0, -1.0, 1.0, 1.0]),   # UR: base_link turned 180° about z
}


def fixed_frames(model) -> dict:
    """Every frame that does not move with a joint: name → 4×4 placement in the root.

    Parameters
    ----------
    model : pinocchio.Model
        Read from the URDF.
    """
    import pinocchio as pin

    data = model.createData()
    pin.framesForwardKinematics(model, data, pin.neutral(model))
    return {f.name: data.oMf[i].homogeneous.copy() for i, f in enumerate(model.frames)
            if f.parentJoint == 0 and f.name != "universe"}


def frame_placement(robot, name: str) -> np.ndarray:
    """Placement (4×4, m) of the frame ``name`` in the robot base frame (the URDF root).

    A point ``p`` given in that frame is ``T[:3, :3] @ p + T[:3, 3]`` in the base frame.

    Parameters
    ----------
    robot : Robot
        Read from a URDF (``robot.source``), whose frames are searched first.
    name : str
        A fixed URDF frame, or ``base_link``/``base`` (:data:`CONVENTIONS`).

    Raises
    ------
    ModelError
        ``name`` moves with a joint, or is neither a URDF frame nor a convention
        (the message lists the frames there are).

    Examples
    --------
    >>> frame_placement(robot, "base")[:3, :3].round(6)      # doctest: +SKIP
    array([[-1., -0.,  0.], [ 0., -1.,  0.], [ 0.,  0.,  1.]])
    """
    model = None
    if robot.source and Path(robot.source).is_file():
        import pinocchio as pin

        model = pin.buildModelFromUrdf(str(robot.source))
    frames = {} if model is None else fixed_frames(model)
    if name in frames:
        return frames[name]
    if name in CONVENTIONS:
        return CONVENTIONS[name].copy()
    moving = ""
    if model is not None and model.existFrame(name):
        joint = model.names[model.frames[model.getFrameId(name)].parentJoint]
        moving = f"; {name!r} moves with joint {joint}: a file's frame must be fixed to the base"
    known = sorted(set(frames) | set(CONVENTIONS))
    raise ModelError(f"no fixed frame {name!r} in {robot.source or robot.name}{moving}; frames "
                     f"there are {', '.join(known)}")


def transform_points(placement, points) -> np.ndarray:
    """Points (K, 3) given in a frame placed at ``placement`` (4×4), in the base frame, m."""
    t = np.asarray(placement, float)
    return np.atleast_2d(np.asarray(points, float)) @ t[:3, :3].T + t[:3, 3]

