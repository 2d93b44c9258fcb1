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

A plane of given position (a point c and a unit normal n, in the frame of the readings) is
not eliminated: its touch's residual is ``ρ = n·(c − x)`` itself, carried as ``ρ·n`` with
the rows ``n ⊗ nᵀB`` (:func:`given_plane_targets`, :func:`given_plane_rows`), and the
plane costs no observation.

After a fit, each plane of unknown position is said as its unit normal n and its distance d
from the frame's origin (the plane ``nᵀx = d``, n turned so that d ≥ 0), ± 1σ
(:func:`located_planes`).
"""
from __future__ import annotations

import re

import numpy as np

from doe_calib.errors import DataError
from doe_calib.estimation.variable_projection import project_out
from doe_calib.io.measurements import MIN_TOUCHES
from doe_calib.model.evaluation import observation_matrix

#: How the note of :func:`plane_note` begins.
_NOTE = re.compile(r"\d+ plane touches on \d+ planes ")
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


def given_plane_targets(points: np.ndarray, point: np.ndarray,
                        normal: np.ndarray) -> np.ndarray:
    """The foot of each of ``points`` (n, 3), m, on its given plane through ``point`` (n, 3),
    m, with unit ``normal`` (n, 3)."""
    return points - normal * np.sum((points - point) * normal, axis=1, keepdims=True)


def given_plane_rows(normal: np.ndarray, b: np.ndarray) -> np.ndarray:
    """Rows B′ = n ⊗ nᵀB (n, 3, P) of touches of given planes with unit ``normal`` (n, 3):
    −B′/σ is the Jacobian of their weighted residuals ρ·n/σ; ``b`` (n, 3, P) their rows of
    the observation matrix."""
    return normal[:, :, None] * np.einsum("ki,kip->kp", normal, b)[:, None, :]


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


def located_planes(model, measurements, params, covariance, noise_scale: float = 1.0) -> dict:
    """Plane id → (normal (3,), its std (3,), distance d from the origin, m, its std, m), in
    the frame of the readings (the robot's root frame when every reading is a contact).

    The plane is the best through the model's points of its touches at ``params``
    (:func:`fitted_plane`). Its shift and two tilts ``a`` (the columns ``A`` of the module
    notes, σ⁻²-weighted) have the covariance ``noise_scale (AᵀWA)⁻¹ + M Σ Mᵀ``, the
    touches' own scatter and the fitted parameters', ``M = (AᵀWA)⁻¹AᵀW nᵀB`` how the plane
    follows the parameters (free columns) and Σ ``covariance`` (free parameters, SI);
    mapped to n and d by ``δn = −a₁e₁ − a₂e₂``, ``δd = a₀ − a₁e₁ᵀc − a₂e₂ᵀc``.
    ``noise_scale``: (σ̂/σ)² when σ is estimated from the residuals, else 1.
    """
    x, b = observation_matrix(model, params.values, measurements.configurations)
    c, j = measurements.config, measurements.marker
    out = {}
    for k in measurements.planes_used.tolist():
        at = measurements.plane == k
        points, w = x[c[at], j[at]], measurements.sigma[at] ** -2.0
        centre, axes, _ = fitted_plane(points, w)
        normal, d = axes[2], float(axes[2] @ centre)
        own = np.c_[np.ones(len(points)), (points - centre) @ axes[:2].T]
        inverse = np.linalg.inv(own.T @ (own * w[:, None]))
        along = np.einsum("i,kip->kp", normal, b[c[at], j[at]][:, :, params.free])
        moved = inverse @ own.T @ (along * w[:, None])
        cov = moved @ covariance @ moved.T + inverse * noise_scale
        to_nd = np.zeros((4, 3))
        to_nd[:3, 1:] = -axes[:2].T
        to_nd[3] = [1.0, -axes[0] @ centre, -axes[1] @ centre]
        std = np.sqrt(np.diag(to_nd @ cov @ to_nd.T))
        sign = -1.0 if d < 0 else 1.0
        out[measurements.plane_names[k]] = (sign * normal, std[:3], sign * d, float(std[3]))
    return out


def is_plane_note(text: str) -> bool:
    """Whether ``text`` is a fit's :func:`plane_note` (each fit has its own)."""
    return bool(_NOTE.match(text))


def plane_note(model, measurements, params, covariance, noise_scale: float = 1.0) -> str:
    """How many touches on how many planes, and where the fit puts each plane: its normal
    and its distance from the frame's origin, mm, ± 1σ (:func:`located_planes`); "" without
    touches.

    Examples
    --------
    >>> plane_note(model, measurements, result.parameters, result.covariance)  # doctest: +SKIP
    '60 plane touches on 3 planes (60 coordinates, less 9 for the planes' unknown …'
    """
    k = len(measurements.planes_used)
    if not k:
        return ""
    n = int(np.sum(measurements.touch & ~measurements.given_plane))
    where = "; ".join(
        f"{name}: normal ({', '.join(f'{v:.6f}' for v in normal)}) ± "
        f"({', '.join(f'{v:.6f}' for v in normal_std)}), {d * 1000.0:.3f} ± "
        f"{d_std * 1000.0:.3f} mm from the origin, "
        f"{int(np.sum(measurements.plane == measurements.plane_names.index(name)))} touches"
        for name, (normal, normal_std, d, d_std) in located_planes(
            model, measurements, params, covariance, noise_scale).items())
    frame = ("the robot's root frame, placed by the fixed base and first joint; the ± leaves "
             "out what contacts cannot see" if measurements.contact.all() else "the tracker frame")
    return (f"{n} plane touches on {k} planes ({n} coordinates, less {3 * k} for the planes' "
            f"unknown positions and tilts, in the observations counted): {where} ({frame})")
