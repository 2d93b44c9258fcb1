"""The compensated program written through the exporters of :mod:`doe_calib.export` (any format).

A compensated row carries the wrench of its load in the base frame, which
turns with the pose; the load itself — the mass and centre of mass the
operator hangs — is recovered from it (:func:`row_loads`), so the program
changes the load only where the load changes and declares its payload there,
and the collision check hangs it on the flange as a sphere of its declared
radius (else a steel sphere of its mass).
"""
from __future__ import annotations

import math
from collections import Counter
from dataclasses import replace

import numpy as np

from doe_calib.design.result import DesignResult
from doe_calib.export import Payload, Plan, export_design
from doe_calib.io.measurements import Configurations
from doe_calib.model.evaluation import evaluate
from doe_calib.model.loads import GRAVITY

#: A compensated program keeps the targets' order and adds no pre-poses.
AS_GIVEN = Plan(group_by="none", order="design", alternate=False)
#: Horizontal share of a force beyond which it is not a hanging mass's.
HORIZONTAL = 1e-6


def _flange_rotations(model, q) -> np.ndarray:
    """Flange orientation in the base frame at each q (nominal parameters), shape (M, 3, 3)."""
    cfg = Configurations.from_arrays(q)
    values = model.nominal().values
    origin = evaluate(model.point_robot, cfg, values, np.zeros(3))[0][:, :, 0]
    axes = [evaluate(model.point_robot, cfg, values, e)[0][:, :, 0] - origin for e in np.eye(3)]
    return np.stack(axes, axis=2)


def row_loads(q, wrench, model=None) -> list:
    """The load of each row as ``KG@X,Y,Z`` (mm, flange frame), "" unloaded, None unknown.

    Rows whose force is vertical (gravity, −z of the base frame) are grouped
    by the mass ``m = −f_z / g`` it gives (to 1e-6 kg); each group's centre of
    mass c solves ``M_i = (R_i c) × F_i`` over its rows in the least-squares
    sense (``R_i`` the nominal flange orientation of ``model``; with all rows
    at one orientation the part of c along the force is not seen and is 0).
    Without ``model`` the centre of mass is not known and the load's spec is
    ``KG@`` only for grouping (no payload declared). A force that is not
    vertical is no hanging mass: None.

    Parameters
    ----------
    q : ndarray, shape (M, N)
        rad (m).
    wrench : ndarray, shape (M, 6)
        N, N·m at the flange origin, base frame.
    model : Model, optional
    """
    import pinocchio as pin

    wrench = np.asarray(wrench, float)
    out = [None] * len(wrench)
    groups = {}
    for r, w in enumerate(wrench):
        f = w[:3]
        if not np.any(w):
            out[r] = ""
        elif np.hypot(f[0], f[1]) <= HORIZONTAL * abs(f[2]) and f[2] < 0:
            groups.setdefault(round(-f[2] / GRAVITY, 6), []).append(r)
    rotations = None if model is None else _flange_rotations(model, np.asarray(q, float))
    for mass, rows in groups.items():
        if rotations is None:
            spec = f"{mass:.6g}@"
        else:
            a = np.vstack([-pin.skew(wrench[r, :3]) @ rotations[r] for r in rows])
            b = np.concatenate([wrench[r, 3:] for r in rows])
            com = np.linalg.lstsq(a, b, rcond=None)[0]
            spec = f"{mass:.6g}@" + ",".join(f"{1000 * c:.6g}" for c in com)
        for r in rows:
            out[r] = spec
    return out


def compensated_design(result, tool, model=None, radius: float | None = None) -> DesignResult:
    """The compensated rows as a design the exporters can write, in the program's order.

    A pose id that appears on several rows (one pose under several loads) gets
    ``_<k>`` appended, since each row has its own q′. A row whose target
    was not reached keeps its programmed q (the solver's last iterate is no
    joint value to send to a robot). Each row's load is named from its wrench
    (:func:`row_loads`, with ``model`` for the centre of mass), so rows under
    the same load are one load case; ``radius`` (m) is the declared size of each
    load whose centre of mass is known, the sphere the collision check draws it as
    (None: a steel sphere of its mass).
    """
    counts, seen, ids = Counter(result.pose), Counter(), []
    for pose in result.pose:
        seen[pose] += 1
        ids.append(pose if counts[pose] == 1 else f"{pose}_{seen[pose]}")
    q = np.where(result.converged[:, None], result.q_compensated, result.q)
    cfg = Configurations.from_arrays(q, result.wrench, pose=ids)
    loads = row_loads(result.q, result.wrench, model)
    if radius is not None:
        loads = [s + f":{1000.0 * radius:g}" if s and not s.endswith("@") else s for s in loads]
    return DesignResult(robot=result.robot, tool=tool, model=result.model, configurations=cfg,
                        criterion="compensated", value=math.nan, bound=math.nan,
                        efficiency=math.nan, predicted_std={},
                        constraints={"row_loads": loads},
                        given_notes=("compensated program (doe-calib compensate)",))


def export_compensated(result, tool, fmt: str, out, name: str = "compensated", dwell: float = 0.0,
                       handshake: int | None = None, model=None, home=None, load_pose=None,
                       trigger: str | None = None, tool_payload: Payload | None = None,
                       design=None, visits=None) -> list:
    """Write the compensated program with :func:`doe_calib.export.export_design`.

    The rows keep their order (:data:`AS_GIVEN`): it is the user's program,
    not a measurement plan. ``home`` and ``load_pose`` (rad/m; None: none)
    are the :class:`~doe_calib.export.Plan`'s; ``model`` names the loads'
    centres of mass (:func:`row_loads`); ``trigger`` and ``tool_payload`` are
    :func:`~doe_calib.export.export_design`'s ``trigger`` and ``tool``;
    ``design`` and ``visits``: the :func:`compensated_design` and its visits
    as :func:`~doe_calib.export.check_program` checked them (default: made
    here, unchecked). Returns the files written.
    """
    design = compensated_design(result, tool, model) if design is None else design
    return export_design(design, fmt, out, name=name, dwell=dwell, handshake=handshake,
                         plan=compensated_plan(home, load_pose), visits=visits, trigger=trigger,
                         tool=tool_payload)


def compensated_plan(home=None, load_pose=None) -> Plan:
    """:data:`AS_GIVEN` from ``home`` to ``home`` through ``load_pose`` (rad/m; None: none)."""
    return replace(AS_GIVEN, home=home, load_pose=load_pose)
