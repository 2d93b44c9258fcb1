"""Socket contacts after a fit: where each socket is, and the note that says so.

A socket's point is not a parameter of the fit (the residuals eliminate it:
:mod:`~doe_calib.estimation.weighted_residuals`); at the fitted parameters it is the
σ⁻²-weighted mean of the model's points of its contacts.
"""
from __future__ import annotations

import re

import numpy as np

from doe_calib.estimation.ballbar import pivot_spread
from doe_calib.estimation.weighted_residuals import socket_mean
from doe_calib.model.evaluation import observation_matrix


#: How the note of :func:`socket_note` begins.
_NOTE = re.compile(r"\d+ socket contacts( and \d+ ballbar lengths)? in \d+ sockets ")


def is_socket_note(text: str) -> bool:
    """Whether ``text`` is a fit's :func:`socket_note` (each fit has its own: a refit's
    replaces it)."""
    return bool(_NOTE.match(text))


def located_sockets(model, measurements, params, covariance, noise_scale: float = 1.0) -> dict:
    """Socket id → (point (3,), std (3,)), m, in the frame of the readings (the robot's
    root frame when every reading is a contact: the base pose is then the identity).

    The point is the σ⁻²-weighted mean ŝ of the model's points of the socket's contacts at
    ``params`` (with ballbar readings, the pivot, which
    :func:`~doe_calib.estimation.ballbar.pivot_spread` gives with the terms below); its
    covariance ``noise_scale / Σσ⁻² · I + B̄ Σ B̄ᵀ``, B̄ the same mean of the
    contacts' observation matrices (free columns) and Σ ``covariance`` (free parameters,
    SI): the contacts' own scatter and the fitted parameters', independent to first order
    (the parameters see only each contact's departure from its socket's mean).
    ``noise_scale``: (σ̂/σ)² when σ is estimated from the residuals, else 1.
    """
    x, b = observation_matrix(model, params.values, measurements.configurations)
    c, j, every = measurements.config, measurements.marker, np.arange(len(measurements))
    points = socket_mean(measurements, every, x[c, j])
    mean_b = socket_mean(measurements, every, b[c, j][:, :, params.free])
    out = {}
    for k in measurements.sockets_used.tolist():
        at = measurements.socket == k
        i = int(np.argmax(at))
        point, moved, own = points[i], mean_b[i], \
            np.eye(3) / np.sum(measurements.sigma[at] ** -2.0)
        if measurements.ballbar[at].any():  # a pivot: the centre of its lengths' spheres
            point, moved, own = pivot_spread(
                x[c, j][at], np.nan_to_num(measurements.distance[at], nan=0.0),
                measurements.sigma[at] ** -2.0, b[c, j][at][:, :, params.free])
        cov = moved @ covariance @ moved.T + own * noise_scale
        out[measurements.socket_names[k]] = (point, np.sqrt(np.diag(cov)))
    return out


def socket_note(model, measurements, params, covariance, noise_scale: float = 1.0) -> str:
    """How many contacts in how many sockets, and where the fit puts each socket, mm, ± 1σ
    (:func:`located_sockets`); "" without contacts.

    Examples
    --------
    >>> socket_note(model, measurements, result.parameters, result.covariance)  # doctest: +SKIP
    '45 socket contacts in 3 sockets (135 coordinates, less 9 for the sockets' unknown …'
    """
    k = len(measurements.sockets_used)
    if not k:
        return ""
    n = int(np.sum((measurements.socket >= 0) & ~measurements.ballbar))
    where = "; ".join(
        f"{name} at ({', '.join(f'{c:.3f}' for c in point * 1000.0)}) ± "
        f"({', '.join(f'{c:.3f}' for c in std * 1000.0)}) mm, "
        f"{int(np.sum(measurements.socket == measurements.socket_names.index(name)))} contacts"
        for name, (point, std) in located_sockets(model, measurements, params, covariance,
                                                  noise_scale).items())
    frame = ("the robot's root frame, placed by the fixed base and first joint; the ± leaves "
             "out what contacts cannot see" if measurements.contact.all() else "the tracker frame")
    bars = int(measurements.ballbar.sum())
    lengths = f" and {bars} ballbar lengths" if bars else ""
    return (f"{n} socket contacts{lengths} in {k} sockets ({3 * n + bars} coordinates, less "
            f"{3 * k} for the sockets' unknown points, in the observations counted): {where} "
            f"({frame})")
