"""Socket contacts after a fit: where each socket is, and the note that says so.

A socket's point is not a parameter of the fit (the residuals eliminate it:
:mod:`~doe_calib.estimation.weighted_residuals`); at the fitted parameters it is the
σ⁻²-weighted mean of the model's points of its contacts.
"""
from __future__ import annotations

import re

import numpy as np

from doe_calib.estimation.weighted_residuals import socket_mean
from doe_calib.model.evaluation import observation_matrix


#: How the note of :func:`socket_note` begins.
_NOTE = re.compile(r"\d+ socket contacts in \d+ sockets[ ,]")


def is_socket_note(text: str) -> bool:
    """Whether ``text`` is a fit's :func:`socket_note` (each fit has its own: a refit's
    replaces it)."""
    return bool(_NOTE.match(text))


def located_sockets(model, measurements, params, covariance, noise_scale: float = 1.0) -> dict:
    """Socket id → (point (3,), std (3,)), m, in the frame of the readings (the robot's
    root frame when every reading is a contact: the base pose is then the identity).

    The point is the σ⁻²-weighted mean ŝ of the model's points of the socket's contacts at
    ``params``; its covariance ``noise_scale / Σσ⁻² · I + B̄ Σ B̄ᵀ``, B̄ the same mean of the
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
        cov = mean_b[i] @ covariance @ mean_b[i].T + \
            np.eye(3) * noise_scale / np.sum(measurements.sigma[at] ** -2.0)
        out[measurements.socket_names[k]] = (points[i], np.sqrt(np.diag(cov)))
    return out


def socket_note(model, measurements, params, covariance, noise_scale: float = 1.0) -> str:
    """How many contacts in how many sockets, and where the fit puts each socket, mm, ± 1σ
    (:func:`located_sockets`); "" without contacts.

    Examples
    --------
    >>> socket_note(model, measurements, result.parameters, result.covariance)  # doctest: +SKIP
    '45 socket contacts in 3 sockets (135 coordinates, less 9 for the unknown sockets' …'
    """
    if not measurements.contact.any():
        return ""
    seated = measurements.socket >= 0
    n, k = int(seated.sum()), len(np.unique(measurements.socket[seated]))
    unknown = len(measurements.sockets_used)
    where = "; ".join(
        f"{name} at ({', '.join(f'{c:.3f}' for c in point * 1000.0)}) ± "
        f"({', '.join(f'{c:.3f}' for c in std * 1000.0)}) mm, "
        f"{int(np.sum(measurements.socket == measurements.socket_names.index(name)))} contacts"
        for name, (point, std) in located_sockets(model, measurements, params, covariance,
                                                  noise_scale).items())
    if measurements.contact.all():
        frame = ("the robot's root frame, placed by the fixed base and first joint; the ± "
                 "leaves out what contacts cannot see")
    elif seated.all():
        frame = "the frame of the given socket positions"
    else:
        frame = "the tracker frame"
    given = f", {k - unknown} of given position" if k > unknown else ""
    return (f"{n} socket contacts in {k} sockets{given} ({3 * n} coordinates, less "
            f"{3 * unknown} for the unknown sockets' points, in the observations counted): "
            f"{where} ({frame})")
