"""Plane touches: each plane, of unknown position, eliminated (formats.md §3, *Plane touches*).

A touch says that the marker (a ball's centre) lay on a plane: one residual, the signed
distance ``ρ = n·(c − x)`` of the model's point x to the plane through c with unit
normal n. With the robot parameters held, the plane is the best through the model's
points of its touches: total least squares, σ⁻²-weighted (c their weighted centroid, n
their direction of least weighted scatter). The Jacobian is the projection
(:mod:`~doe_calib.estimation.variable_projection`) of ``−nᵀB/σ`` off the plane's own
directions ``[1, e₁ᵀ(x − c), e₂ᵀ(x − c)]/σ`` (its shift along n and its two tilts, e₁ and
e₂ the in-plane principal directions).

The residual is carried as the 3-vector ``ρ·n`` (from the model's point to its foot on the
plane), the Jacobian as ``n ⊗ ∂ρ``: n being a unit vector, the normal equations are those
of the scalars, and a touch keeps the point layout (3 rows) of every other reading.
"""
from __future__ import annotations

import numpy as np

from doe_calib.errors import DataError
from doe_calib.estimation.variable_projection import project_out
from doe_calib.io.measurements import MIN_TOUCHES
#: A plane's touches whose scatter across their main direction is below this fraction of the
#: scatter along it lie on a line: the plane's tilt about that line is not seen.
MIN_SPREAD_RATIO = 0.01


def fitted_plane(points: np.ndarray, weights: np.ndarray) -> tuple:
    """The best plane through ``points`` (n, 3), m, weighted by ``weights`` (n,) (σ⁻²).

    Returns
    -------
    centre : ndarray, shape (3,)
        The weighted centroid, m.
    axes : ndarray, shape (3, 3)
        Rows e₁, e₂ (in the plane, most scatter first) and the normal n.
    scatter : ndarray, shape (3,)
        Weighted sums of squares along each axis, m² (× weight), descending.

    Examples
    --------
    >>> pts = np.array([[0.0, 0, 0], [1, 0, 0], [0, 2, 0], [1, 2, 0]])
    >>> np.abs(fitted_plane(pts, np.ones(4))[1][2]).tolist()
    [0.0, 0.0, 1.0]
    """
    centre = weights @ points / weights.sum()
    d = points - centre
    values, vectors = np.linalg.eigh((d * weights[:, None]).T @ d)  # ascending
    return centre, vectors[:, ::-1].T, values[::-1]


def plane_targets(points: np.ndarray, weights: np.ndarray) -> np.ndarray:
    """The foot on the best plane of each of ``points`` (n, 3), m: what it is compared to."""
    centre, axes, _ = fitted_plane(points, weights)
    normal = axes[2]
    return points - np.outer((points - centre) @ normal, normal)


def plane_rows(points: np.ndarray, sigma: np.ndarray, b: np.ndarray) -> np.ndarray:
    """Rows B′ (n, 3, P) of the touches of one plane, such that −B′/σ is the Jacobian of
    their weighted residuals ρ·n/σ (module notes); ``b`` (n, 3, P) their rows of the
    observation matrix, ``points`` their model points (m), ``sigma`` (n,) m."""
    centre, axes, _ = fitted_plane(points, sigma ** -2.0)
    normal = axes[2]
    along = np.einsum("i,kip->kp", normal, b) / sigma[:, None]
    own = np.c_[np.ones(len(points)), (points - centre) @ axes[:2].T] / sigma[:, None]
    return normal[None, :, None] * (project_out(own, along) * sigma[:, None])[:, None, :]


def check_planes(measurements, points: np.ndarray) -> None:
    """Refuse a plane with fewer than :data:`MIN_TOUCHES` touches, or whose touches'
    model ``points`` (K, 3) lie on a line (:data:`MIN_SPREAD_RATIO`).

    Raises
    ------
    DataError
        Naming the plane, its touches' lines and the file.
    """
    for k in measurements.planes_used.tolist():
        at = np.flatnonzero(measurements.plane == k)
        name, lines = measurements.plane_names[k], _lines(measurements.line[at])
        if len(at) < MIN_TOUCHES:
            raise DataError(f"plane {name!r} has {len(at)} touches ({lines}): a plane takes 3 "
                            f"to place; touch it at {MIN_TOUCHES} points or more",
                            measurements.source or "<measurements>")
        scatter = fitted_plane(points[at], measurements.sigma[at] ** -2.0)[2]
        if not scatter[1] > MIN_SPREAD_RATIO ** 2 * scatter[0]:
            raise DataError(f"plane {name!r}: its {len(at)} touches ({lines}) lie on a line, "
                            f"which leaves the plane's tilt about it unknown; touch the plane "
                            f"at points spread over it", measurements.source or "<measurements>")


def _lines(lines) -> str:
    shown = ", ".join(str(n) for n in lines[:6].tolist())
    return f"lines {shown}{', …' if len(lines) > 6 else ''}"
