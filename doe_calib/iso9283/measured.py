"""The attained poses of a measured ISO 9283 test, from tracker readings, per campaign.

Each configuration whose pose id is a visit (``P3-07``) gives one attained position (the
TCP marker's reading) and, when three markers or more are read there, one attained
orientation of the flange (the rotation that best carries the tool's markers onto the
readings, least squares). Readings are taken into the robot base frame by the inverse of
the tracker pose of the base (``x_base = R_bᵀ (x − t_b)``), or used as they are.
Campaigns are the readings' sessions (a ``session`` column, or one file each), in the
order measured.
"""
from __future__ import annotations

import numpy as np
from scipy.spatial.transform import Rotation

from doe_calib.errors import DataError
from doe_calib.iso9283.plan import parse_visit
from doe_calib.iso9283.result import Campaign
from doe_calib.model.rotations import rotation_vector_to_matrix


def campaigns(meas, plan, markers, base=None) -> tuple:
    """The :class:`~.result.Campaign` of each session of ``meas``.

    Configurations whose pose id is not a visit (a home pose, a check point) and visits
    without a reading of the TCP are left out.

    Parameters
    ----------
    meas : Measurements
        Readings of the test (tracker frame, or the base frame when ``base`` is None).
    plan : IsoPlan
    markers : dict
        Marker name → its position on the flange (3,), m (nominal or identified), in the
        order of the tool the readings were read with (``meas.marker`` indexes it): the
        orientation's reference.
    base : array_like, shape (6,), optional
        Tracker pose of the robot base, ``[t (m), rotation vector (rad)]``.

    Raises
    ------
    DataError
        No visit read at the TCP in a session, or a visit read twice in one.
    """
    rotation, origin = (np.eye(3), np.zeros(3)) if base is None else \
        (rotation_vector_to_matrix(np.asarray(base[3:], float)), np.asarray(base[:3], float))
    in_base = (meas.xyz - origin) @ rotation   # Rᵀ (x − t), row by row
    tool_names = list(markers)
    sessions = meas.sessions
    out = {}
    for c, pose_id in enumerate(meas.configurations.pose):
        visit = parse_visit(pose_id)
        if visit is None:
            continue
        rows = np.flatnonzero(meas.config == c)
        read = {tool_names[meas.marker[r]]: 1000.0 * in_base[r] for r in rows}
        if plan.tcp not in read:
            continue
        runs = out.setdefault(sessions[c], {})
        pose, cycle = visit
        if cycle in runs.setdefault(pose, {}):
            raise DataError(f"session {sessions[c]!r}: visit {pose_id} is read twice (with "
                            f"different loads?); an ISO 9283 test reads each visit once",
                            meas.source)
        runs[pose][cycle] = (read[plan.tcp], _orientation(read, markers))
    if not out:
        raise DataError(f"no visit P1-01 … P5-{plan.cycles:02d} read at the TCP marker "
                        f"{plan.tcp!r}: is this the test's data?", meas.source)
    return tuple(_campaign(name, runs, plan) for name, runs in out.items())


def _orientation(read: dict, markers: dict) -> np.ndarray | None:
    """The flange rotation carrying ``markers`` (m) onto the readings (mm), from 3 or more."""
    if len(read) < 3:
        return None
    seen = list(read)
    y = np.array([read[n] for n in seen]) / 1000.0
    m = np.array([markers[n] for n in seen], float)
    return Rotation.align_vectors(y - y.mean(0), m - m.mean(0))[0].as_matrix()


def _campaign(name: str, runs: dict, plan) -> Campaign:
    poses = [p for p in plan.targets_mm if p in runs]
    cycles = {p: np.array(sorted(runs[p])) for p in poses}
    x = {p: np.array([runs[p][c][0] for c in cycles[p]]) for p in poses}
    turned = all(runs[p][c][1] is not None for p in poses for c in cycles[p])
    rot = {p: np.array([runs[p][c][1] for c in cycles[p]]) for p in poses} if turned else None
    return Campaign.from_cycles(str(name), x, {p: plan.targets_mm[p] for p in poses}, cycles,
                                rot, {p: plan.rotation(p) for p in poses})
