"""Symbolic rotations (CasADi SX) and their numeric counterparts.

``rotation_vector``: exact exponential map (no small-angle assumption) used
for the tracker/base frame, which may be turned by any angle.
"""
from __future__ import annotations

import casadi as ca
import numpy as np
from scipy.spatial.transform import Rotation


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


def matrix_to_rotation_vector(rotation: np.ndarray) -> np.ndarray:
    """Rotation vector (rad) of a 3×3 rotation matrix."""
    return Rotation.from_matrix(rotation).as_rotvec()


def rotation_vector_to_matrix(r) -> np.ndarray:
    """3×3 rotation matrix of a rotation vector (rad)."""
    return Rotation.from_rotvec(np.asarray(r, float)).as_matrix()


def skew_matrix(v) -> np.ndarray:
    """[v]× for a numeric 3-vector."""
    return np.array([[0.0, -v[2], v[1]], [v[2], 0.0, -v[0]], [-v[1], v[0], 0.0]])
