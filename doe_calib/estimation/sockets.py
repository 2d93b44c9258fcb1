"""Socket contacts after a fit: where each socket is, the note that says so, and what a
prediction from contacts alone is relative to.

A socket's point is not a parameter of the fit (the residuals eliminate it:
:mod:`~doe_calib.estimation.weighted_residuals`); at the fitted parameters it is the
σ⁻²-weighted mean of the model's points of its contacts.

A fit to contacts alone cannot see a rigid motion of the whole (unless three given
socket positions not on one line place it) nor its scale (unless two given positions
are apart): :func:`~doe_calib.estimation.preparation.fix_unseen_by_contacts` and
:func:`~doe_calib.estimation.preparation.fix_base_turn` fixed parameters for them. Its predictions are relative to the sockets' frame, and their
std is honest only there: the parameters the rank analysis could not separate are
taken up by the free ones up to such a motion (:func:`frame_unseen_part`), which is
said in words (:func:`frame_words`), not put in the number.
"""
from __future__ import annotations

import re

import numpy as np

from doe_calib.estimation.ballbar import pivot_spread
from doe_calib.estimation.preparation import LINE_UNSEEN, POINT_UNSEEN
from doe_calib.estimation.unseen import given_tolerances, tolerances, unseen_part
from doe_calib.estimation.weighted_residuals import socket_mean
from doe_calib.model.evaluation import observation_matrix

#: What the words of a fit to readings without coordinates say when it fixed the base pose,
#: and the scale (:func:`~doe_calib.estimation.preparation.unseen_words`, any instrument).
BASE_WORDS, SCALE_WORDS = "cannot see the robot's base pose", "cannot see the robot's scale"


#: How the note of :func:`socket_note` begins.
_NOTE = re.compile(r"\d+ socket contacts( and \d+ ballbar lengths)? in \d+ sockets[ ,]")


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
    if measurements.socket is None or not (measurements.socket >= 0).any():
        return ""
    seated = measurements.socket >= 0
    n = int(np.sum(seated & ~measurements.ballbar))
    k, unknown = len(np.unique(measurements.socket[seated])), len(measurements.sockets_used)
    if not unknown:
        return (f"{n} socket contacts in {k} sockets of given position ({3 * n} coordinates, "
                f"in the frame of {'the tracker' if not seated.all() else 'the positions'})")
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
    bars = int(measurements.ballbar.sum())
    lengths = f" and {bars} ballbar lengths" if bars else ""
    given = f", {k - unknown} of given position" if k > unknown else ""
    return (f"{n} socket contacts{lengths} in {k} sockets{given} ({3 * n + bars} coordinates, "
            f"less {3 * unknown} for the unknown sockets' points, in the observations "
            f"counted): {where} ({frame})")


def frame_reasons(params) -> list[str]:
    """The reasons ``params`` (a result's) hold for what a fit to contacts alone cannot
    see (:mod:`~doe_calib.estimation.preparation`'s words), each once; [] for another fit."""
    turns = (POINT_UNSEEN, LINE_UNSEEN.split("{")[0])
    return [w for w in dict.fromkeys(params.fixed_reason)
            if w.startswith(turns) or BASE_WORDS in w or SCALE_WORDS in w]


def from_contacts(result) -> bool:
    """Whether ``result`` was fitted from socket contacts (its socket note, or what a fit
    to contacts alone fixes)."""
    return any(is_socket_note(w) for w in result.warnings) or bool(
        frame_reasons(result.parameters))


def frame_unseen_part(model, params, markers=None, tolerance: dict | None = None,
                      within=None):
    """The unseen part of a fit from socket contacts, relative to the sockets' frame.

    As :func:`~doe_calib.estimation.unseen.unseen_part`, but a not-separable parameter
    is taken up by the free parameters and by those held for what contacts alone cannot
    see (:func:`frame_reasons`: a rigid motion of the whole, its scale; the fit cannot
    see these either, and :func:`frame_words` says so). The part's ``free`` are the
    parameters that take up, so ``part.effect`` of any point (a marker, a TCP, in either
    frame) leaves out that motion; what they leave is its unseen part (a single ball
    seen off the flange's axis leaves some 0.3 % of what it cannot separate).
    """
    return unseen_part(model, params, markers, tolerance,
                       taking=np.isin(params.fixed_reason, frame_reasons(params)), within=within)


def frame_words(params, tolerance: dict | None = None) -> str:
    """What a prediction of a fit to contacts alone is relative to, in words ("" for
    another fit): the motion of the whole its readings cannot see, and the scale's
    stated tolerance per metre, neither in the std."""
    reasons = frame_reasons(params)
    if not reasons:
        return ""
    words = []
    if any(BASE_WORDS in w for w in reasons):
        words.append("relative to the sockets' frame: where the robot stands in it (a rigid "
                     "motion of every point) is not seen")
    elif POINT_UNSEEN in reasons:
        words.append("relative to the frame of the given socket position: a turn of every "
                     "point about that socket is not seen")
    elif any(w.startswith(LINE_UNSEEN.split("{")[0]) for w in reasons):
        line = next(w for w in reasons if w.startswith(LINE_UNSEEN.split("{")[0]))
        words.append(f"relative to the frame of the given socket positions: a turn of every "
                     f"point about their line ({line.rsplit('(', 1)[-1].rstrip(')')}) is not "
                     f"seen")
    held = [(n, w) for n, w in zip(params.names, params.fixed_reason)
            if SCALE_WORDS in w]
    if held:
        name, why = held[0]
        length = float(why.rsplit("(", 1)[-1].split()[0]) / 1000.0
        tol = float(tolerances(params, [name], tolerance)[0])
        whose = "stated tolerance" if given_tolerances(params, [name], tolerance)[0] else \
            "tolerance not given, the typical deviation"
        words.append(f"the scale is not seen (no known length): ±{tol / length * 1000.0:.3g} "
                     f"mm per metre of distance (1σ; {name} held at the URDF's, "
                     f"{whose} {tol * 1000.0:.3g} mm over {length * 1000.0:.1f} mm)")
    return "; ".join(words) + ("; neither is in the std" if len(words) > 1 else
                               ", nor in the std")
