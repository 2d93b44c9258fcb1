"""Campaigns without a tracker, simulated independently of our model (numpy + Pinocchio).

The truth is issue #31's: a UR10 with every joint placement off by a rigid transform (up to
0.5 mm and 0.05° on each axis), joint offsets up to 0.1°, the tool's ball centre 1 mm off its
nominal 100 mm on the flange axis. Each reading is a configuration that puts the *true* ball
centre where the instrument holds it (damped Gauss–Newton on the truth, from a random start,
so the tool's orientation varies), and only the controller's joint values are logged, as a
user's robot would:

- **sockets**: the ball seated in a socket (seating scatter per axis);
- **planes**: the ball touching a flat face (scatter along the face's normal);
- **ballbar**: the ball at a measured distance from a pivot socket (length read to 1 µm).
"""
from __future__ import annotations

import csv
from dataclasses import replace
from pathlib import Path

import numpy as np

#: Nominal ball centre on the flange, m.
BALL_M = np.array([0.0, 0.0, 0.10])
#: Sockets on the table, m, in the robot's root frame (issue #31).
SOCKETS_M = {"S1": [0.65, 0.25, 0.05], "S2": [0.45, -0.55, 0.05], "S3": [-0.25, 0.70, 0.05]}
#: Faces touched: (a point on the face, its unit normal, the half-size of the touched patch), m.
PLANES_M = {"table": ([0.55, 0.0, 0.02], [0.0, 0.0, 1.0], 0.25),
            "block_x": ([0.45, 0.45, 0.25], [-1.0, 0.0, 0.0], 0.12),
            "block_y": ([0.30, -0.60, 0.25], [0.0, 1.0, 0.0], 0.12)}
#: Ballbar pivots, m, and the bar's lengths, m.
PIVOTS_M = {"P1": [0.55, 0.20, 0.05], "P2": [-0.10, 0.65, 0.05]}
LENGTHS_M = (0.15, 0.225, 0.30)
#: Every joint turns at most half a turn either way (a hand-guided cobot's range of use).
WITHIN = np.c_[-np.pi * np.ones(6), np.pi * np.ones(6)]


def truth(sim, chain, seed: int = 31):
    """Issue #31's UR10 truth (the independent simulator's), drawn from ``seed``."""
    return sim.ball_on_stem_truth(chain, seed=seed)


def ball(sim, chain, t, q) -> np.ndarray:
    """True ball centres (M, 3), m, at configurations q (M, 6), rad."""
    q = np.atleast_2d(q)
    return sim.marker_positions(chain, t, q, np.zeros((len(q), 6)))[:, 0]


def seat(sim, chain, t, target, rng, start=None):
    """A configuration (6,), rad, that puts the true ball centre on ``target`` (3,), m, from
    ``start`` (6,), rad, or a random start, or None when it does not converge."""
    q = sim.random_configurations(chain, 1, rng, within=WITHIN)[0] if start is None else start
    for _ in range(60):
        e = np.asarray(target) - ball(sim, chain, t, q)[0]
        if np.linalg.norm(e) < 1e-12:
            return (q + np.pi) % (2 * np.pi) - np.pi
        h = 1e-7
        jac = np.array([(ball(sim, chain, t, q + d)[0] - ball(sim, chain, t, q - d)[0]) / (2 * h)
                        for d in np.eye(6) * h]).T
        q = q + jac.T @ np.linalg.solve(jac @ jac.T + 1e-6 * np.eye(3), e)
    return None


def stem_angle_deg(sim, chain, t, q, axis=None) -> float:
    """Angle, deg, between the tool's stem (flange origin → true ball centre) at q (6,), rad,
    and the unit ``axis`` (3,) (default the downward vertical)."""
    flange = replace(t, markers=np.zeros((1, 3)))
    stem = ball(sim, chain, t, q)[0] - ball(sim, chain, flange, q)[0]
    along = -stem[2] if axis is None else np.dot(stem, axis)
    return float(np.degrees(np.arccos(np.clip(along / np.linalg.norm(stem), -1.0, 1.0))))


def _seated(sim, chain, t, targets, rng, cone_deg=None, clear=None, axes=None):
    """The configuration reaching each target, in order; a target that fails, whose stem
    leans more than ``cone_deg`` from the downward vertical (or from its row of ``axes``
    (K, 3), unit), or whose configuration ``clear(q)`` refuses, is retried from another
    start."""
    out = []
    for k, target in enumerate(targets):
        axis = None if axes is None else axes[k]
        q = None
        while q is None or (cone_deg is not None
                            and stem_angle_deg(sim, chain, t, q, axis) > cone_deg) or \
                (clear is not None and not clear(q)):
            q = seat(sim, chain, t, target, rng)
        out.append(q)
    return np.array(out)


def designed_socket_rows(sim, chain, t, design: dict, seating_mm: float, rng):
    """Rows of a contact design's contacts (its JSON, formats.md §4) as the robot seats them:
    from each designed configuration, the ball brought home into its socket on the truth."""
    rows = []
    for pose in design["poses"]:
        target = (np.asarray(SOCKETS_M[pose["socket"]])
                  + rng.normal(scale=seating_mm * 1e-3, size=3))
        q = seat(sim, chain, t, target, rng, start=np.radians(pose["q_deg"]))
        if q is None:
            raise RuntimeError(f"designed contact {pose['pose']} does not seat on the truth")
        rows.append({"pose": pose["pose"], **q_columns(q), "marker": "ball",
                     "socket": pose["socket"], "x": "", "y": "", "z": ""})
    return rows


def designed_plane_rows(sim, chain, t, design: dict, scatter_mm: float, rng):
    """Rows of a touch design's touches (its JSON, formats.md §4) as the robot makes them:
    from each designed configuration, the true ball brought along its face's normal onto
    the face (off it by a normal scatter of ``scatter_mm``)."""
    rows = []
    for pose in design["poses"]:
        point, normal, _ = PLANES_M[pose["plane"]]
        n = np.asarray(normal, float)
        start = np.radians(pose["q_deg"])
        here = ball(sim, chain, t, start)[0]
        target = here - (n @ (here - point) - rng.normal(scale=scatter_mm * 1e-3)) * n
        q = seat(sim, chain, t, target, rng, start=start)
        if q is None:
            raise RuntimeError(f"designed touch {pose['pose']} does not reach its face")
        rows.append({"pose": pose["pose"], **q_columns(q), "marker": "ball",
                     "plane": pose["plane"]})
    return rows


def designed_ballbar_rows(sim, chain, t, design: dict, reading_mm: float, rng):
    """Rows of a ballbar design's positions (its JSON, formats.md §4) as the robot makes
    them: at each designed configuration, the length the bar reads to the true ball (the
    true distance, read to ``reading_mm``)."""
    rows = []
    for pose in design["poses"]:
        q = np.radians(pose["q_deg"])
        true = np.linalg.norm(ball(sim, chain, t, q)[0] - PIVOTS_M[pose["socket"]])
        rows.append({"pose": pose["pose"], **q_columns(q), "marker": "ball",
                     "socket": pose["socket"],
                     "distance": repr(float(1e3 * true + rng.normal(scale=reading_mm)))})
    return rows


def socket_rows(sim, chain, t, per_socket: int, seating_mm: float, rng, given=(),
                cone_deg=None, clear=None):
    """Rows of ``per_socket`` contacts in each socket, seated from random starts (with
    ``cone_deg``, only those whose stem comes down within that angle of the vertical; with
    ``clear``, only configurations ``clear(q)`` accepts); the
    sockets named in ``given`` carry their drawing position (x, y, z, mm), the others leave
    x, y, z empty."""
    rows = []
    for name, point in SOCKETS_M.items():
        targets = np.asarray(point) + rng.normal(scale=seating_mm * 1e-3, size=(per_socket, 3))
        for k, q in enumerate(_seated(sim, chain, t, targets, rng, cone_deg, clear)):
            xyz = [repr(1e3 * v) for v in point] if name in given else ["", "", ""]
            rows.append({"pose": f"{name}-{k + 1}", **q_columns(q), "marker": "ball",
                         "socket": name, "x": xyz[0], "y": xyz[1], "z": xyz[2]})
    return rows


def plane_rows(sim, chain, t, per_plane: int, scatter_mm: float, rng, cone_deg=None,
               clear=None):
    """Rows of ``per_plane`` touches of each face, at random points of its patch (with
    ``cone_deg``, only those whose stem comes within that angle of the inward normal; with
    ``clear``, only configurations ``clear(q)`` accepts)."""
    rows = []
    for name, (point, normal, half) in PLANES_M.items():
        n = np.asarray(normal, float)
        a = np.cross(n, [1.0, 0.0, 0.0] if abs(n[0]) < 0.9 else [0.0, 1.0, 0.0])
        a /= np.linalg.norm(a)
        b = np.cross(n, a)
        uv = rng.uniform(-half, half, size=(per_plane, 2))
        targets = (np.asarray(point) + uv[:, :1] * a + uv[:, 1:] * b
                   + rng.normal(scale=scatter_mm * 1e-3, size=(per_plane, 1)) * n)
        for k, q in enumerate(_seated(sim, chain, t, targets, rng, cone_deg, clear,
                                      np.tile(-n, (per_plane, 1)))):
            rows.append({"pose": f"{name}-{k + 1}", **q_columns(q), "marker": "ball",
                         "plane": name})
    return rows


def ballbar_rows(sim, chain, t, per_length: int, reading_mm: float, rng, cone_deg=None,
                 clear=None):
    """Rows of ``per_length`` positions of the bar's tool end for each pivot and length,
    directions drawn over the upper half sphere (with ``cone_deg``, only those whose stem
    comes within that angle of the bar, towards the pivot; with ``clear``, only
    configurations ``clear(q)`` accepts); the logged length is read to ``reading_mm``."""
    rows = []
    for name, pivot in PIVOTS_M.items():
        for length in LENGTHS_M:
            d = rng.normal(size=(per_length, 3))
            d[:, 2] = np.abs(d[:, 2]) + 0.3
            d /= np.linalg.norm(d, axis=1, keepdims=True)
            targets = np.asarray(pivot) + length * d
            for k, q in enumerate(_seated(sim, chain, t, targets, rng, cone_deg, clear, -d)):
                true = np.linalg.norm(ball(sim, chain, t, q)[0] - pivot)
                rows.append({"pose": f"{name}-{int(length * 1e3)}-{k + 1}", **q_columns(q),
                             "marker": "ball", "socket": name,
                             "distance": repr(float(1e3 * true + rng.normal(scale=reading_mm)))})
    return rows


def q_columns(q) -> dict:
    """``q1`` … ``q6`` in degrees, as a controller logs them."""
    return {f"q{k + 1}": repr(float(v)) for k, v in enumerate(np.degrees(q))}


def write_rows(path: Path, rows) -> Path:
    """Rows (dicts) to a measurement CSV whose columns are every key met, in order."""
    columns = list(dict.fromkeys(k for r in rows for k in r))
    with open(path, "w", newline="", encoding="utf-8") as fh:
        writer = csv.DictWriter(fh, fieldnames=columns, restval="")
        writer.writeheader()
        writer.writerows(rows)
    return path


def registered_rms_mm(predicted, true, scale: bool = False) -> float:
    """3-D RMS, mm, of ``predicted`` − ``true`` (K, 3), m, after the best rigid motion of the
    predicted points onto the true ones (Kabsch); with ``scale`` the best similarity
    (Umeyama)."""
    a, b = predicted - predicted.mean(0), true - true.mean(0)
    u, s, vt = np.linalg.svd(a.T @ b)
    d = np.diag([1.0, 1.0, np.sign(np.linalg.det(u @ vt))])
    rot = (u @ d @ vt).T
    grow = np.trace(np.diag(s) @ d) / np.sum(a * a) if scale else 1.0
    return float(np.sqrt(np.mean(np.sum((grow * a @ rot.T - b) ** 2, axis=1))) * 1e3)
