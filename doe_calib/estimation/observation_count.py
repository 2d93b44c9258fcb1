"""How many coordinates readings give, by kind, and whether they are enough for a fit.

A reading of a point (a tracker's, or a socket contact) gives 3 coordinates, a plane touch
or a ballbar length 1 (along the plane's normal, along the bar); each socket, plane or pivot
of unknown position costs 3, estimated with the fit, a plane of given position nothing
(formats.md §3). The readings are
counted against the parameters they separate (the rank analysis), not against every free
one, when none has coordinates: touches of three faces see some 18 of a UR10's 43 free
geometric parameters.
"""
from __future__ import annotations

import numpy as np

from doe_calib.errors import DataError

#: What to do when the readings are too few, in words.
MEASURE_MORE = "measure more poses or markers, or use a smaller model"
#: The readings' kinds and unknown points counted (:func:`reading_counts`).
COUNTED = ("contacts", "touches", "lengths", "sockets", "planes", "pivots")


def reading_counts(measurements) -> dict:
    """The readings without coordinates and the unknown points they are read against, by kind
    (:data:`COUNTED`): socket contacts (in sockets of unknown position), plane touches,
    ballbar lengths; sockets of unknown position (ballbar pivots not counted), planes,
    pivots.

    Examples
    --------
    >>> reading_counts(touches)  # doctest: +SKIP
    {'contacts': 0, 'touches': 60, 'lengths': 0, 'sockets': 0, 'planes': 3, 'pivots': 0}
    """
    m = measurements
    pivots = np.unique(m.socket[m.ballbar]) if m.ballbar.any() else np.zeros(0, int)
    return {"contacts": int(np.sum(m.contact & ~m.touch & ~m.ballbar)),
            "touches": int(np.sum(m.touch)), "lengths": int(np.sum(m.ballbar)),
            "sockets": len(np.setdiff1d(m.sockets_used, pivots)),
            "planes": len(m.planes_used), "pivots": len(pivots)}


def coordinate_words(measurements) -> str:
    """How the observed coordinates are counted, in words, each kind said only when present
    (``1 for each of 40 plane touches, less 3 for each of 3 planes of unknown position``)."""
    if measurements.observed_per_configuration:
        return f"{measurements.observed_per_configuration} per pose"
    n = reading_counts(measurements)
    k = int(np.sum(~(measurements.touch | measurements.ballbar)))
    parts = [f"3 for each of {k} points read" + (" or socket contacts" if n["contacts"] else "")
             ] if k else []
    given = int(np.sum(measurements.given_plane))
    parts += [f"1 for each of {n[key]} {what}" for key, what in (
        ("touches", "plane touches" + (f" ({given} on planes of given position)" if given
                                       else "")),
        ("lengths", "ballbar lengths")) if n[key]]
    unknown = [f"{n[key]} {key if n[key] > 1 else key[:-1]}"
               for key in ("sockets", "planes", "pivots") if n[key]]
    return ", ".join(parts) + (f", less 3 for each of {' and '.join(unknown)} of unknown "
                               f"position" if unknown else "")


def check_count(measurements, params, ident=None) -> None:
    """Refuse, in words, readings too few for the free ``params``.

    Before the rank analysis (``ident`` None), readings some of which have coordinates (a
    tracker's, a socket's of given position) are counted against every free parameter;
    readings all without coordinates only need one coordinate left. After it (``ident``
    the rank analysis), readings all without coordinates are counted against the parameters
    they separate: the coordinates bound that rank, and with a single point read per
    configuration they reach it. Readings that separate as many parameters as they have
    coordinates, some found not separable, may only be too few: one coordinate more than the
    parameters separated is asked for, as a design of contacts asks.

    Raises
    ------
    DataError
        With the count in words (:func:`coordinate_words`) and how many coordinates it
        takes at least.
    """
    n, n_free = measurements.n_coordinates, int(params.free.sum())
    words = f"{n} observed coordinates for {n_free} unknown parameters " \
            f"({coordinate_words(measurements)})"
    where = measurements.source or "<measurements>"
    read = (~measurements.contact).any()
    if ident is None and (n < n_free if read else n < 1):
        raise DataError(f"{words}: {MEASURE_MORE}", where)
    if ident is None or read or ident.rank < n or not ident.dependent:
        return
    raise DataError(f"{words}: they separate as many parameters as they have coordinates, too "
                    f"few to tell which of the other {n_free - ident.rank} they cannot see and "
                    f"which want more readings (at least {ident.rank + 1} coordinates, and up "
                    f"to {n_free + 1} if every free parameter is seen): {MEASURE_MORE}", where)
