"""Point-set registration: the rigid motion that best maps one point set onto another."""
from __future__ import annotations

import numpy as np


def register(source, target, weights=None):
    """Least-squares rigid transform with ``target ≈ R @ source + t``.

    Kabsch: the SVD of the weighted cross-covariance, as SciPy's
    ``Rotation.align_vectors`` computes it.

    Parameters
    ----------
    source, target : array_like, shape (K, 3)
        Corresponding points, metres. At least 3 points not on one line.
    weights : array_like, shape (K,), optional

    Returns
    -------
    R : ndarray (3, 3)
    t : ndarray (3,), metres
    """
    source, target = np.asarray(source, float), np.asarray(target, float)
    w = np.ones(len(source)) if weights is None else np.asarray(weights, float)
    cs = np.average(source, axis=0, weights=w)
    ct = np.average(target, axis=0, weights=w)
    u, _, vt = np.linalg.svd((w[:, None] * (target - ct)).T @ (source - cs))
    if np.linalg.det(u @ vt) < 0:  # a reflection: turn the least certain axis instead
        u[:, -1] = -u[:, -1]
    r = u @ vt
    return r, ct - r @ cs
