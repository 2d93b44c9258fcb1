"""Readings without coordinates simulated: the joint values that seat the true ball in its
socket or on its plane, and the lengths a ballbar logs.

A contact (formats.md §3, *Socket contacts*) is a ball on the tool pushed by hand into a
socket on the table. The controller logs the joint values where the ball came to rest:
those of the *true* robot with the ball in the socket, not those of the nominal model.
A simulated contact therefore starts from the planned (nominal) q and moves it until the
true model's ball sits on the socket's point, give or take the seating scatter: damped
Gauss–Newton on the joint values, the ball's Jacobian in q by central differences, the
minimum-norm step (a 6-joint arm has 3 joint directions to spare: the tool's orientation
stays close to the plan). A configuration holding several contacts (several balls each in
its socket) seats them together.

A plane touch (*Plane touches*) is seated alike, on the foot of the true ball (at the
planned q) on its plane, give or take a scatter along the normal. A ballbar reading
(*Ballbar and gauge lengths*) is a commanded q and a measured length: its q is logged as
planned and its length is the true ball's distance from the pivot, give or take the noise.

A socket of given position (its rows carry the drawing's x, y, z, in the frame of the
readings: the tracker's, or the socket plate's) is where the truth's base transform puts
that point, moved by one draw of the drawing's tolerance (``socket_sigma``) common to its
contacts: the plate as made, not as drawn. Its rows keep the drawing's position.

Where the unknowns are, unless given: a socket's point is where the truth puts the ball on
average over its seated contacts at their planned q; a plane is the best (least-squares)
plane through the true ball's points at its touches' planned q; a pivot is the mean of its
seated contacts' true ball points or, with none, the centre that best fits the true ball's
points at the planned q to the template's lengths (the algebraic sphere fit, linear in the
centre and its squared norm).
"""
from __future__ import annotations

import numpy as np

from doe_calib.errors import DataError
from doe_calib.io.measurements import Configurations, Measurements
from doe_calib.model.evaluation import marker_positions

#: Distance (m) from its target within which a ball counts as seated.
SEATED_M = 1e-12
#: Gauss–Newton iterations allowed to seat the balls.
MAX_ITERATIONS = 50
#: Central-difference step in each joint, rad or m.
_STEP = 1e-6


def socket_points(model, values, template) -> dict:
    """Socket id → point (3,), m, frame of the readings, where the true model (``values``,
    SI) puts it (module notes): the ball's mean over the socket's seated contacts at their
    planned q; a pivot without seated contacts, the centre best fitting the template's
    lengths."""
    x = marker_positions(model, values, template.configurations)
    points = x[template.config, template.marker]
    bar = template.ballbar
    out = {}
    for k in template.sockets_used.tolist():
        mine = template.socket == k
        seated = mine & ~bar
        out[template.socket_names[k]] = points[seated].mean(axis=0) if seated.any() else \
            _sphere_centre(points[mine], template.distance[mine])
    return out


def plane_points(model, values, template) -> dict:
    """Plane id → (a point on it (3,), its unit normal (3,)), m, frame of the readings: the
    best plane through the true ball's points (``values``, SI) at its touches' planned q."""
    x = marker_positions(model, values, template.configurations)
    points = x[template.config, template.marker]
    out = {}
    for k in template.planes_used.tolist():
        mine = points[template.plane == k]
        centre = mine.mean(axis=0)
        out[template.plane_names[k]] = (centre, np.linalg.svd(mine - centre)[2][-1])
    return out


def _sphere_centre(points, lengths) -> np.ndarray:
    """The centre s (3,) best fitting ``|x − s| = L`` to ``points`` (n, 3) and ``lengths``
    (n,), m: least squares on ``2xᵀs − |s|² = |x|² − L²``."""
    a = np.c_[2.0 * points, -np.ones(len(points))]
    return np.linalg.lstsq(a, np.sum(points ** 2, axis=1) - lengths ** 2, rcond=None)[0][:3]


def given_rows(template) -> np.ndarray:
    """Which readings of ``template`` are contacts in a socket of given position (its x, y, z
    on the row), shape (K,) bool."""
    if template.socket is None:
        return np.zeros(len(template), bool)
    return (template.socket >= 0) & np.isfinite(template.xyz[:, 0]) & ~template.ballbar


def seated_configurations(model, values, template, targets) -> Configurations:
    """The template's configurations with the joint values that put the ball of each seated
    contact (in a socket of unknown or given position) and each plane touch on its target
    (module notes); configurations without one are kept as they are.

    Parameters
    ----------
    model : Model
    values : ndarray, shape (P,)
        The true parameters, SI.
    template : Measurements
        Which configurations, markers, sockets and planes; their q are the planned ones.
    targets : ndarray, shape (K, 3)
        Where each seated contact's or touch's ball is to sit, m (rows of tracker readings
        and ballbar lengths are ignored).

    Raises
    ------
    DataError
        A contact or a touch the true robot cannot seat from its planned q (out of reach, or
        at a singular configuration), naming its pose.
    """
    rows = np.flatnonzero(template.contact & ~template.ballbar | given_rows(template))
    cfg = template.configurations
    if rows.size == 0:
        return cfg
    used, local = np.unique(template.config[rows], return_inverse=True)
    sub = cfg.subset(used)
    q = sub.q.copy()
    n = q.shape[1]
    steps = np.vstack([np.zeros(n), np.eye(n) * _STEP, -np.eye(n) * _STEP])  # (2N + 1, N)
    stacked = sub.subset(np.tile(np.arange(len(used)), len(steps)))
    for _ in range(MAX_ITERATIONS):
        moved = np.repeat(steps, len(used), axis=0) + np.tile(q, (len(steps), 1))
        x = marker_positions(model, values, Configurations(stacked.pose, moved, stacked.wrench,
                                                           stacked.env))
        x = x.reshape(len(steps), len(used), *x.shape[1:])[:, local, template.marker[rows]]
        error = targets[rows] - x[0]                                     # (R, 3)
        if np.max(np.linalg.norm(error, axis=1)) < SEATED_M:
            break
        jac = np.moveaxis((x[1:n + 1] - x[n + 1:]) / (2 * _STEP), 0, -1)  # (R, 3, N)
        for c in range(len(used)):
            mine = local == c
            j, e = jac[mine].reshape(-1, n), error[mine].ravel()
            q[c] += j.T @ np.linalg.solve(j @ j.T + 1e-12 * np.eye(len(e)), e)
    else:
        worst = int(np.argmax(np.linalg.norm(error, axis=1)))
        i = rows[worst]
        where = f"on plane {template.plane_names[template.plane[i]]}" if template.touch[i] \
            else f"in socket {template.socket_names[template.socket[i]]}"
        raise DataError(f"pose {cfg.pose[used[local[worst]]]}: the true robot cannot seat "
                        f"its ball {where}"
                        f" from the planned joint values ({np.linalg.norm(error[worst]) * 1e3:.3g}"
                        f" mm off after {MAX_ITERATIONS} iterations): out of reach or at a "
                        f"singular configuration", template.source or None,
                        int(template.line[rows[worst]]))
    out = cfg.q.copy()
    out[used] = q
    return Configurations(cfg.pose, out, cfg.wrench, cfg.env)


def simulate_readings(model, values, template, sigma: float, rng=None, points=None,
                      source: str = "simulated", planes=None) -> Measurements:
    """The readings of ``template`` simulated on the true model (module notes): tracker
    readings with Gaussian noise; socket contacts seated (:func:`seated_configurations`) on
    their socket's point plus a seating scatter (a given point moved by a draw of its
    ``socket_sigma`` first), plane touches on their plane plus a scatter
    along its normal, their logged q the seated ones; ballbar lengths at their planned q,
    the true distance from the pivot plus noise.

    Parameters
    ----------
    model : Model
    values : array_like, shape (P,) or ParameterSet
        True parameter values, SI.
    template : Measurements
        Which configurations (planned q, loads), markers and sockets; its x, y, z are not
        used but on the rows of a socket of given position (with its ``socket_sigma``).
    sigma : float
        Noise σ per coordinate of a tracker reading, seating scatter per axis of a contact,
        scatter along the normal of a touch, noise of a length, m.
    rng : numpy.random.Generator, optional
    points : dict, optional
        Socket id → point (3,) (a pivot's for ballbar lengths), m, frame of the readings;
        default :func:`socket_points`.
    planes : dict, optional
        Plane id → (a point on it (3,), m, its normal (3,)); default :func:`plane_points`.

    Raises
    ------
    DataError
        A socket or plane of the template not in ``points`` or ``planes``; a contact or
        touch the true robot cannot seat (:func:`seated_configurations`).

    Returns
    -------
    Measurements
        The template's readings in its order, readings without coordinates without x, y, z
        (NaN), contacts in a socket of given position with the template's x, y, z and
        ``socket_sigma``.
    """
    rng = np.random.default_rng() if rng is None else rng
    values = np.asarray(getattr(values, "values", values), float)
    where = _given("socket", template.socket_names, template.sockets_used,
                   socket_points(model, values, template) if points is None else points,
                   template)
    flat = _given("plane", template.plane_names, template.planes_used,
                  plane_points(model, values, template) if planes is None else planes, template)
    contact, bar, touch = template.contact, template.ballbar, template.touch
    targets = np.full((len(template), 3), np.nan)
    for k in template.sockets_used.tolist():
        targets[template.socket == k] = np.asarray(where[template.socket_names[k]], float)
    given = given_rows(template)
    for k in np.unique(template.socket[given]).tolist() if given.any() else ():
        at = given & (template.socket == k)
        tolerance = 0.0 if template.socket_sigma is None else template.socket_sigma[at][0]
        targets[at] = template.xyz[at][0] + tolerance * rng.standard_normal(3)
    seated = contact & ~bar & ~touch | given
    targets[seated] += sigma * rng.standard_normal((int(seated.sum()), 3))
    if touch.any():
        planned = marker_positions(model, values, template.configurations)
        planned = planned[template.config, template.marker]
        for k in template.planes_used.tolist():
            at = template.plane == k
            centre, normal = (np.asarray(v, float) for v in flat[template.plane_names[k]])
            normal = normal / np.linalg.norm(normal)
            off = (planned[at] - centre) @ normal - sigma * rng.standard_normal(int(at.sum()))
            targets[at] = planned[at] - np.outer(off, normal)
    cfg = seated_configurations(model, values, template, targets)
    x = marker_positions(model, values, cfg)[template.config, template.marker]
    xyz = np.where(contact[:, None], np.nan,
                   x + sigma * rng.standard_normal((len(template), 3)))
    xyz[given] = template.xyz[given]
    distance = None
    if template.distance is not None:
        distance = np.full(len(template), np.nan)
        distance[bar] = np.linalg.norm(x[bar] - targets[bar], axis=1) + \
            sigma * rng.standard_normal(int(bar.sum()))
    return Measurements(cfg, template.config, template.marker, xyz,
                        np.full(len(template), sigma if sigma > 0 else 1e-6),
                        np.zeros(len(template), int), source, socket=template.socket,
                        socket_names=template.socket_names, plane=template.plane,
                        plane_names=template.plane_names, distance=distance,
                        socket_sigma=template.socket_sigma)


def _given(kind, names, used, given, template) -> dict:
    """``given`` (id → where) once every used id of ``kind`` is in it.

    Raises
    ------
    DataError
        Naming the first ``kind`` (socket, plane) with no entry.
    """
    for k in used.tolist():
        if names[k] not in given:
            what = "point" if kind == "socket" else "plane"
            raise DataError(f"no {what} given for {kind} {names[k]!r} ({what}s for "
                            f"{', '.join(map(repr, given)) or 'none'})", template.source or None)
    return given
