"""Socket contacts simulated: the joint values that seat the true ball in its socket.

A contact (formats.md §3, *Socket contacts*) is a ball on the tool pushed by hand into a
socket on the table. The controller logs the joint values where the ball came to rest:
those of the *true* robot with the ball in the socket, not those of the nominal model.
A simulated contact therefore starts from the planned (nominal) q and moves it until the
true model's ball sits on the socket's point, give or take the seating scatter: damped
Gauss–Newton on the joint values, the ball's Jacobian in q by central differences, the
minimum-norm step (a 6-joint arm has 3 joint directions to spare: the tool's orientation
stays close to the plan). A configuration holding several contacts (several balls each in
its socket) seats them together.
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
    """Socket id → point (3,), m, frame of the readings: where the true model (``values``,
    SI) puts the ball on average over the socket's contacts at their planned q."""
    x = marker_positions(model, values, template.configurations)
    points = x[template.config, template.marker]
    return {template.socket_names[k]: points[template.socket == k].mean(axis=0)
            for k in template.sockets_used.tolist()}


def seated_configurations(model, values, template, targets) -> Configurations:
    """The template's configurations with the joint values that put each contact's ball on
    its target (module notes); configurations without a contact are kept as they are.

    Parameters
    ----------
    model : Model
    values : ndarray, shape (P,)
        The true parameters, SI.
    template : Measurements
        Which configurations, markers and sockets (:attr:`Measurements.socket`); their q are
        the planned ones.
    targets : ndarray, shape (K, 3)
        Where each contact's ball is to sit, m (rows of tracker readings are ignored).

    Raises
    ------
    DataError
        A contact the true robot cannot seat from its planned q (out of reach, or at a
        singular configuration), naming its pose.
    """
    rows = np.flatnonzero(template.contact)
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
        raise DataError(f"pose {cfg.pose[used[local[worst]]]}: the true robot cannot seat "
                        f"its ball in socket {template.socket_names[template.socket[rows[worst]]]}"
                        f" from the planned joint values ({np.linalg.norm(error[worst]) * 1e3:.3g}"
                        f" mm off after {MAX_ITERATIONS} iterations): out of reach or at a "
                        f"singular configuration", template.source or None,
                        int(template.line[rows[worst]]))
    out = cfg.q.copy()
    out[used] = q
    return Configurations(cfg.pose, out, cfg.wrench, cfg.env)


def simulate_readings(model, values, template, sigma: float, rng=None, points=None,
                      source: str = "simulated") -> Measurements:
    """The readings of ``template`` simulated on the true model: tracker readings with
    Gaussian noise; socket contacts seated (:func:`seated_configurations`) on their socket's
    point plus a seating scatter, their logged q the seated ones.

    Parameters
    ----------
    model : Model
    values : array_like, shape (P,) or ParameterSet
        True parameter values, SI.
    template : Measurements
        Which configurations (planned q, loads), markers and sockets; its x, y, z are not
        used.
    sigma : float
        Noise σ per coordinate of a tracker reading, and seating scatter per axis of a
        contact, m.
    rng : numpy.random.Generator, optional
    points : dict, optional
        Socket id → point (3,), m, frame of the readings; default :func:`socket_points`.

    Raises
    ------
    DataError
        A socket of the template without a point in ``points``; a contact the true robot
        cannot seat (:func:`seated_configurations`).

    Returns
    -------
    Measurements
        The template's readings in its order, contacts without x, y, z (NaN).
    """
    rng = np.random.default_rng() if rng is None else rng
    values = np.asarray(getattr(values, "values", values), float)
    where = socket_points(model, values, template) if points is None else points
    contact = template.contact
    targets = np.full((len(template), 3), np.nan)
    for k in template.sockets_used.tolist():
        name = template.socket_names[k]
        if name not in where:
            raise DataError(f"no point given for socket {name!r} (points for "
                            f"{', '.join(map(repr, where)) or 'none'})", template.source or None)
        targets[template.socket == k] = np.asarray(where[name], float)
    targets[contact] += sigma * rng.standard_normal((int(contact.sum()), 3))
    cfg = seated_configurations(model, values, template, targets)
    x = marker_positions(model, values, cfg)[template.config, template.marker]
    xyz = np.where(contact[:, None], np.nan,
                   x + sigma * rng.standard_normal((len(template), 3)))
    return Measurements(cfg, template.config, template.marker, xyz,
                        np.full(len(template), sigma if sigma > 0 else 1e-6),
                        np.zeros(len(template), int), source, socket=template.socket,
                        socket_names=template.socket_names)
