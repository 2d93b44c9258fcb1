"""The observation matrix through the flange's twist: six reverse sweeps, not 3n.

Every marker moves with the flange: ``x_j = t + R u_j`` in the tracker frame
(``R``, ``t``: the flange pose there, ``u_j``: marker j on the flange). For a
parameter ``p_k`` of the base or the robot, ``∂R/∂p_k = [ω_k]× R`` with
``[ω_k]× = (∂R/∂p_k) Rᵀ`` skew because R is a rotation, so

``∂x_j/∂p_k = ∂t/∂p_k + ω_k × (R u_j)``,   ``∂x_j/∂u_j = R``.

The Jacobian of the six numbers ``(t, ω)`` takes six reverse sweeps of the
flange's expression graph, whatever the number of markers; CasADi's own
``jacobian(x, p)`` takes one per marker coordinate (nine for three markers).
For the full 6R model with 3 markers: 19 453 operations per pose instead of
26 642, the same matrix to rounding (``tests/test_twist_jacobian.py``).

It holds when ``R`` is an exact rotation at every parameter value, as the
built-in effects make it (exact exponential maps and axis-angle matrices); an
effect whose ``placement`` may return any 3×3 matrix (a user effect's
``flange_correction``) says so with ``exact_rotations = False``, and the
model then takes CasADi's ``jacobian``; so it does with one or two markers
(three or six sweeps of its own), and it keeps the shorter of the two for
small models (:data:`~doe_calib.model.marker_model.TWIST_SURELY_SHORTER`).
"""
from __future__ import annotations

import casadi as ca

from doe_calib.model.rotations import skew

#: (row b, row c) of ``(∂R/∂p) Rᵀ`` holding ω_x, ω_y, ω_z.
_OMEGA = ((2, 1), (0, 2), (1, 0))


def marker_jacobian(rot: ca.SX, pos: ca.SX, p: ca.SX, markers) -> ca.SX:
    """∂x/∂p of every marker (3n × P, SX) from the flange pose in the tracker frame.

    Parameters
    ----------
    rot, pos : casadi.SX
        Flange rotation (3×3) and position (3×1, m) in the tracker frame, functions
        of ``p`` but not of the marker positions.
    p : casadi.SX
        All parameters (P×1, SI).
    markers : list of (casadi.SX, slice)
        Each marker's position on the flange (3×1, m), a slice of ``p``, and that slice.
    """
    n_par = p.shape[0]
    seeds = []
    for b, c in _OMEGA:
        s = ca.SX.zeros(3, 3)
        for m in range(3):
            s[b, m] = rot[c, m]
        seeds.append(ca.vec(s))
    j_omega = ca.jtimes(ca.vec(rot), p, ca.horzcat(*seeds), True).T  # 3 × P
    j_pos = ca.jtimes(pos, p, ca.SX.eye(3), True).T  # 3 × P
    rows = []
    for u, where in markers:
        block = j_pos - skew(rot @ u) @ j_omega
        own = ca.SX(3, n_par)
        own[:, where] = rot
        rows.append(block + own)
    return ca.vertcat(*rows)
