"""The formulas of ISO 9283:1998 for pose and distance characteristics, numbers in, numbers out.

For one commanded pose ``(x_c, y_c, z_c)`` reached in ``n`` cycles at ``x_j`` (§7.2):

* position accuracy ``AP = √((x̄ − x_c)² + (ȳ − y_c)² + (z̄ − z_c)²)``, with its
  components ``AP_x = x̄ − x_c``, ``AP_y = ȳ − y_c``, ``AP_z = z̄ − z_c``;
* position repeatability ``RP = l̄ + 3 S_l``, ``l_j = |x_j − x̄|``,
  ``S_l = √(Σ (l_j − l̄)² / (n − 1))``;
* orientation accuracy ``AP_a = ā − a_c`` (and b, c) and repeatability
  ``RP_a = ±3 S_a``, ``S_a = √(Σ (a_j − ā)² / (n − 1))``, with ``a, b, c`` the
  rotations about the base's x, y, z axes (roll, pitch, yaw: ``R = R_z(c) R_y(b) R_x(a)``),
  each cycle's angle taken within ±180° of the commanded one.

Between two commanded poses (§7.3, §7.4: ISO 9283 measures them between P2 and P4), each
cycle's attained distance ``D_j = |x_1j − x_2j|`` against the commanded ``D_c``: distance
accuracy ``AD = |D̄ − D_c|`` and repeatability ``RD = ±3 S_D``.

The test cube (§6): P1 at its centre, P2 … P5 on the diagonal plane through the corners
C1 = (−,−,−), C2 = (+,−,−), C7 = (+,+,+), C8 = (−,+,+) (signs of the corner's offset from
the centre along x, y, z), each at 10 % of the plane's diagonal (the cube's space
diagonal, edge·√3) from its corner, P2 by C1, P3 by C2, P4 by C7, P5 by C8: P2 and P4
are the diagonal's opposite ends.

The functions are unit-blind: lengths come out in the unit they went in (the reports use
mm), angles in radians.
"""
from __future__ import annotations

import numpy as np
from scipy.spatial.transform import Rotation

#: The test poses in the standard's cycle order.
POSES = ("P1", "P2", "P3", "P4", "P5")
#: The pair of poses ISO 9283 measures distance accuracy and repeatability between.
DISTANCE_PAIR = ("P2", "P4")
#: Corner of the diagonal plane each of P2 … P5 sits by: signs of its offset along x, y, z.
CORNERS = {"P2": (-1, -1, -1), "P3": (1, -1, -1), "P4": (1, 1, 1), "P5": (-1, 1, 1)}
#: Distance of P2 … P5 from their corners, as a fraction of the plane's diagonal.
CORNER_FRACTION = 0.1


def cube_points(centre, edge: float) -> dict:
    """P1 … P5 of the cube of ``edge`` centred at ``centre`` (3,), axis-aligned (module notes).

    Examples
    --------
    >>> p = cube_points([0.0, 0.0, 0.0], 1.0)
    >>> p["P1"].tolist(), p["P2"].round(3).tolist()
    ([0.0, 0.0, 0.0], [-0.4, -0.4, -0.4])
    """
    centre = np.asarray(centre, float).reshape(3)
    # a corner lies half the diagonal from the centre: 10 % of it from the corner is 80 %
    # of the way out from the centre
    out = 1.0 - 2.0 * CORNER_FRACTION
    return {"P1": centre, **{p: centre + out * 0.5 * edge * np.array(s, float)
                             for p, s in CORNERS.items()}}


def position_characteristics(attained, commanded) -> dict:
    """AP, its components and RP of one pose.

    Parameters
    ----------
    attained : array_like, shape (n, 3)
        The position reached in each of n ≥ 2 cycles.
    commanded : array_like, shape (3,)

    Returns
    -------
    dict
        ``AP``, ``APx``, ``APy``, ``APz``, ``RP``, ``S_l``, ``l_mean`` and ``mean`` (3,).
    """
    x = np.asarray(attained, float).reshape(-1, 3)
    if len(x) < 2:
        raise ValueError(f"a pose needs 2 cycles or more for its repeatability, got {len(x)}")
    mean = x.mean(axis=0)
    ap = mean - np.asarray(commanded, float).reshape(3)
    lengths = np.linalg.norm(x - mean, axis=1)
    s_l = float(np.std(lengths, ddof=1))
    return {"AP": float(np.linalg.norm(ap)), "APx": float(ap[0]), "APy": float(ap[1]),
            "APz": float(ap[2]), "RP": float(lengths.mean() + 3.0 * s_l), "S_l": s_l,
            "l_mean": float(lengths.mean()), "mean": mean}


def roll_pitch_yaw(rotations) -> np.ndarray:
    """Angles ``(a, b, c)`` (rad) about the base x, y, z of each rotation (…, 3, 3):
    ``R = R_z(c) R_y(b) R_x(a)``; shape (…, 3)."""
    r = np.asarray(rotations, float)
    return Rotation.from_matrix(r.reshape(-1, 3, 3)).as_euler("xyz").reshape(r.shape[:-2] + (3,))


def orientation_characteristics(attained, commanded) -> dict:
    """AP_a, AP_b, AP_c and RP_a, RP_b, RP_c (rad) of one pose.

    Parameters
    ----------
    attained : array_like, shape (n, 3, 3)
        The orientation reached in each of n ≥ 2 cycles (rotation matrices, base frame).
    commanded : array_like, shape (3, 3)

    Returns
    -------
    dict
        ``AP_a`` … ``AP_c`` (``ā − a_c``) and ``RP_a`` … ``RP_c`` (``3 S_a``), rad.
    """
    angles = roll_pitch_yaw(attained).reshape(-1, 3)
    if len(angles) < 2:
        raise ValueError(f"a pose needs 2 cycles or more for its repeatability, got "
                         f"{len(angles)}")
    # each cycle's angle within ±π of the commanded one, so that a mean means something
    delta = np.angle(np.exp(1j * (angles - roll_pitch_yaw(commanded))))
    ap, rp = delta.mean(axis=0), 3.0 * np.std(delta, ddof=1, axis=0)
    return {**{f"AP_{k}": float(v) for k, v in zip("abc", ap)},
            **{f"RP_{k}": float(v) for k, v in zip("abc", rp)}}


def distance_characteristics(first, second, first_commanded, second_commanded) -> dict:
    """AD and RD between two poses reached in the same n ≥ 2 cycles.

    Parameters
    ----------
    first, second : array_like, shape (n, 3)
        The positions reached in each cycle, row j of both in cycle j.
    first_commanded, second_commanded : array_like, shape (3,)

    Returns
    -------
    dict
        ``AD`` (``|D̄ − D_c|``), ``RD`` (``3 S_D``), ``D_mean``, ``D_c``, ``n``.
    """
    x1, x2 = (np.asarray(v, float).reshape(-1, 3) for v in (first, second))
    if len(x1) != len(x2) or len(x1) < 2:
        raise ValueError(f"distance characteristics need the same 2 or more cycles of both "
                         f"poses, got {len(x1)} and {len(x2)}")
    d = np.linalg.norm(x1 - x2, axis=1)
    d_c = float(np.linalg.norm(np.asarray(first_commanded, float)
                               - np.asarray(second_commanded, float)))
    return {"AD": float(abs(d.mean() - d_c)), "RD": float(3.0 * np.std(d, ddof=1)),
            "D_mean": float(d.mean()), "D_c": d_c, "n": int(len(d))}
