"""Symbolic rotations (CasADi SX) and their numeric counterparts.

``rotation_vector``: exact exponential map (no small-angle assumption) used
for the tracker/base frame, which may be turned by any angle. The numeric
conversions follow SciPy's ``Rotation`` (through the unit quaternion, the same
formulas and the same small-angle series) in NumPy: loading
``scipy.spatial`` costs a command half a second.
"""
from __future__ import annotations

import casadi as ca
import numpy as np


def skew(v) -> ca.SX:
    """[v]× for a 3-vector (SX)."""
    return ca.vertcat(ca.horzcat(0, -v[2], v[1]),
                      ca.horzcat(v[2], 0, -v[0]),
                      ca.horzcat(-v[1], v[0], 0))


def axis_angle(axis, angle) -> ca.SX:
    """Rotation by ``angle`` (rad, SX) about a constant unit ``axis`` (Rodrigues)."""
    k = ca.DM(np.asarray(axis, float).reshape(3, 1))
    kx = skew(k)
    return ca.SX.eye(3) + ca.sin(angle) * kx + (1 - ca.cos(angle)) * (kx @ kx)


def rotation_xyz(rx, ry, rz) -> ca.SX:
    """``Rx(rx) Ry(ry) Rz(rz)`` (rad, SX scalars): small placement errors."""
    return axis_angle((1, 0, 0), rx) @ axis_angle((0, 1, 0), ry) @ axis_angle((0, 0, 1), rz)


def rotation_vector(r) -> ca.SX:
    """Exponential map of a rotation vector ``r`` (rad, SX (3,1)), exact at any angle."""
    th2 = ca.dot(r, r)
    small = th2 < 1e-10
    th = ca.sqrt(ca.if_else(small, 1.0, th2))  # guarded: never differentiates sqrt at 0
    a = ca.if_else(small, 1 - th2 / 6, ca.sin(th) / th)
    b = ca.if_else(small, 0.5 - th2 / 24, (1 - ca.cos(th)) / ca.if_else(small, 1.0, th2))
    rx = skew(r)
    return ca.SX.eye(3) + a * rx + b * (rx @ rx)


def _quaternion(rotation: np.ndarray) -> np.ndarray:
    """Unit quaternion (x, y, z, w), w ≥ 0, of an orthogonal 3×3 matrix (Shepperd's method:
    from the largest of the trace and the diagonal, as SciPy)."""
    m = rotation
    trace = m[0, 0] + m[1, 1] + m[2, 2]
    choice = int(np.argmax([m[0, 0], m[1, 1], m[2, 2], trace]))
    q = np.empty(4)
    if choice == 3:
        q[:] = m[2, 1] - m[1, 2], m[0, 2] - m[2, 0], m[1, 0] - m[0, 1], 1 + trace
    else:
        i, j, k = choice, (choice + 1) % 3, (choice + 2) % 3
        q[i] = 1 - trace + 2 * m[i, i]
        q[j] = m[j, i] + m[i, j]
        q[k] = m[k, i] + m[i, k]
        q[3] = m[k, j] - m[j, k]
    q /= np.linalg.norm(q)
    nonzero = q[np.flatnonzero(q[:3])[:1]]
    return -q if q[3] < 0 or (q[3] == 0 and nonzero.size and nonzero[0] < 0) else q


def matrix_to_rotation_vector(rotation: np.ndarray) -> np.ndarray:
    """Rotation vector (rad) of a 3×3 rotation matrix; angle in [0, π].

    A matrix not orthogonal to 1e-12 is replaced by the nearest orthogonal one (SVD).

    Examples
    --------
    >>> r = matrix_to_rotation_vector(rotation_vector_to_matrix([0.1, -0.2, 0.3]))
    >>> bool(np.allclose(r, [0.1, -0.2, 0.3]))
    True
    """
    m = np.asarray(rotation, float)
    if m.shape != (3, 3):
        raise ValueError(f"a rotation matrix is 3×3, got shape {m.shape}")
    if not np.linalg.det(m) > 0:
        raise ValueError(f"not a rotation: the matrix's determinant is {np.linalg.det(m):g} "
                         f"(a left-handed or degenerate frame)")
    if not np.allclose(m @ m.T, np.eye(3), rtol=1e-5, atol=1e-12):
        u, _, vt = np.linalg.svd(m)
        m = u @ vt
    q = _quaternion(m)
    angle = 2 * np.arctan2(np.linalg.norm(q[:3]), q[3])
    if angle <= 1e-3:
        scale = 2 + angle ** 2 / 12 + 7 * angle ** 4 / 2880
    else:
        scale = angle / np.sin(angle / 2)
    return scale * q[:3]


def rotation_vector_to_matrix(r) -> np.ndarray:
    """3×3 rotation matrix of a rotation vector (rad); shape (..., 3) gives (..., 3, 3).

    Examples
    --------
    >>> bool(np.allclose(rotation_vector_to_matrix([0, 0, np.pi / 2]) @ [1, 0, 0], [0, 1, 0]))
    True
    """
    r = np.asarray(r, float)
    if r.shape[-1:] != (3,):
        raise ValueError(f"a rotation vector has 3 components, got shape {r.shape}")
    angle = np.linalg.norm(r, axis=-1, keepdims=True)
    small = angle <= 1e-3
    scale = np.where(small, 0.5 - angle ** 2 / 48 + angle ** 4 / 3840,
                     np.sin(angle / 2) / np.where(small, 1.0, angle))
    x, y, z = np.moveaxis(r * scale, -1, 0)
    w = np.cos(angle[..., 0] / 2)
    x2, y2, z2, w2 = x * x, y * y, z * z, w * w
    xy, zw, xz, yw, yz, xw = x * y, z * w, x * z, y * w, y * z, x * w
    rows = [[x2 - y2 - z2 + w2, 2 * (xy - zw), 2 * (xz + yw)],
            [2 * (xy + zw), -x2 + y2 - z2 + w2, 2 * (yz - xw)],
            [2 * (xz - yw), 2 * (yz + xw), -x2 - y2 + z2 + w2]]
    return np.moveaxis(np.array(rows), (0, 1), (-2, -1))


def skew_matrix(v) -> np.ndarray:
    """[v]× for a numeric 3-vector."""
    return np.array([[0.0, -v[2], v[1]], [v[2], 0.0, -v[0]], [-v[1], v[0], 0.0]])
