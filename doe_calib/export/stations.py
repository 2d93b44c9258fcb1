"""Where a program starts, ends and changes the load: the home and load-change poses.

Both are moves of the program (:class:`.program.Move` of ``kind`` ``"home"`` or
``"load change"``), collision-checked like every other.
"""
from __future__ import annotations

import numpy as np

from doe_calib.errors import OptionError
from doe_calib.export.ordering import axis_speeds, move_times

_LIMIT_TOL = 1e-12  # rad or m


def zero_home(robot, limits=None) -> tuple:
    """The URDF zero clipped inside the joint limits (``limits``: (lower, upper)), rad (m).

    Examples
    --------
    >>> from doe_calib import examples
    >>> from doe_calib.model.robot import Robot
    >>> len(zero_home(Robot.from_urdf(examples.ROBOT_URDF)))
    6
    """
    lower, upper = (robot.lower, robot.upper) if limits is None else limits
    return tuple(float(v) for v in np.clip(np.zeros(robot.n_joints), lower, upper))


def check_station(robot, q, option: str, limits=None) -> tuple:
    """``q`` (URDF values, rad/m) if it has one value per joint inside ``limits`` ((lower,
    upper), rad/m; None: the URDF's); else an OptionError naming ``option`` and the joint."""
    q = np.asarray(q, float)
    if q.shape != (robot.n_joints,) or not np.all(np.isfinite(q)):
        raise OptionError(f"{option}: give {robot.n_joints} finite joint values "
                          f"({', '.join(robot.joint_names)}), deg (mm for prismatic joints)")
    outside = outside_limits(robot, q, *((robot.lower, robot.upper) if limits is None
                                         else limits))
    if outside:
        raise OptionError(f"{option}: {outside}")
    return tuple(float(v) for v in q)


def outside_limits(robot, q, lower, upper) -> str:
    """The first joint of ``q`` (rad/m) outside [``lower``, ``upper``] in words, else ""."""
    for joint, v, lo, hi in zip(robot.joints, q, lower, upper):
        if not lo - _LIMIT_TOL <= v <= hi + _LIMIT_TOL:
            k, unit = joint.display_factor, joint.display_unit
            return (f"joint {joint.name} = {v * k:.6g} {unit} is outside its limits "
                    f"[{lo * k:g}, {hi * k:g}] {unit}")
    return ""


def default_home(design, is_free=None, limits=None) -> tuple:
    """The home pose (rad/m) a program uses when none is given, and why, in words.

    The design's own home when its poses were checked reachable from one; else the URDF
    zero inside ``limits`` (:func:`zero_home`) if ``is_free(q)`` passes it (None: no
    check); else the design pose nearest to it (a UR arm's zero touches its floor).
    """
    reach = (design.constraints or {}).get("reachability") or {}
    if reach.get("home") is not None:  # the design joined every pose to it by a free path
        q = tuple(float(v) for v in np.asarray(reach["home"], float)
                  / design.robot.display_factors)
        if is_free is None or is_free(np.array(q)):
            return q, "home: the design's home pose (every pose was checked reachable from it)"
    zero = zero_home(design.robot, limits)
    if is_free is None or is_free(np.array(zero)):
        return zero, "home: the URDF zero inside the joint limits"
    cfg = design.configurations  # nearest: by the time of the slowest axis
    i = int(np.argmin(move_times(np.asarray(zero, float)[None, :], cfg.q,
                                 axis_speeds(design.robot))[0]))
    return tuple(float(v) for v in cfg.q[i]), (
        f"home: design pose {cfg.pose[i]}, the one nearest the URDF zero (the zero is not free "
        f"of collisions; give --home to choose another)")
