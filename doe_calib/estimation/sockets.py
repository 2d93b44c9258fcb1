"""Socket contacts after a fit: where each socket is, and the note that says so.

A socket's point is not a parameter of the fit (the residuals eliminate it:
:mod:`~doe_calib.estimation.weighted_residuals`); at the fitted parameters it is the
σ⁻²-weighted mean of the model's points of its contacts.
"""
from __future__ import annotations

import re

import numpy as np

from doe_calib.estimation.weighted_residuals import marker_points, socket_mean


#: How the note of :func:`socket_note` begins.
_NOTE = re.compile(r"\d+ socket contacts in \d+ sockets ")


def is_socket_note(text: str) -> bool:
    """Whether ``text`` is a fit's :func:`socket_note` (each fit has its own: a refit's
    replaces it)."""
    return bool(_NOTE.match(text))


def socket_points(model, measurements, values) -> dict:
    """Socket id → its point (3,), m, in the frame of the readings (the robot's root frame
    when every reading is a contact: the base pose is then the identity)."""
    every = np.arange(len(measurements))
    mean = socket_mean(measurements, every, marker_points(model, measurements, values))
    return {measurements.socket_names[k]: mean[np.argmax(measurements.socket == k)]
            for k in measurements.sockets_used.tolist()}


def socket_note(model, measurements, values) -> str:
    """How many contacts in how many sockets, and where the fit puts each socket (mm); ""
    without contacts.

    Examples
    --------
    >>> socket_note(model, measurements, result.parameters.values)   # doctest: +SKIP
    '45 socket contacts in 3 sockets (135 coordinates, less 9 for the sockets' unknown …'
    """
    if not measurements.contact.any():
        return ""
    n, k = int(measurements.contact.sum()), len(measurements.sockets_used)
    where = "; ".join(
        f"{name} at ({', '.join(f'{c:.3f}' for c in point * 1000.0)}) mm, "
        f"{int(np.sum(measurements.socket == measurements.socket_names.index(name)))} contacts"
        for name, point in socket_points(model, measurements, values).items())
    frame = "the robot's root frame" if measurements.contact.all() else "the tracker frame"
    return (f"{n} socket contacts in {k} sockets ({3 * n} coordinates, less {3 * k} for the "
            f"sockets' unknown points, in the observations counted): {where} ({frame})")
