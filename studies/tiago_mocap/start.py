"""Start values for unknown marker positions and base pose, by alternation on the nominal robot."""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from doe_calib.estimation.registration import register
from doe_calib.model.evaluation import evaluate


@dataclass(frozen=True)
class RoughStart:
    """Start values: marker positions u (n, 3) in the flange frame and base (R, p), m."""

    markers: np.ndarray
    rotation: np.ndarray
    translation: np.ndarray
    spread_mm: float
    rms_mm: float


def rough_start(model, measurements, iterations: int = 30) -> RoughStart:
    """Start values for unknown markers and base pose, by alternation on the nominal robot.

    With the flange poses ``(R_f, p_f)`` of the nominal robot and the base
    ``(R_b, p_b)`` (start: ``R_b = I``, ``p_b`` matching the centroids), repeat:

    * markers: ``u_j = mean_i R_fᵀ (R_bᵀ (y_ij − p_b) − p_f)``;
    * base: point-set registration of the predicted ``p_f + R_f u_j`` onto ``y_ij``.

    Each step lowers the sum of squares, so it converges (slowly: base and
    markers trade along weak directions); it only has to land in the basin of
    Levenberg–Marquardt. ``spread_mm`` is the RMS scatter of the per-pose
    estimates of ``u_j`` (the nominal robot's errors, seen in the flange frame).
    """
    cfg, c, j = measurements.configurations, measurements.config, measurements.marker
    y = measurements.xyz
    v = model.nominal().values.copy()
    v[:] = 0.0
    rot_f, pos_f = evaluate(model.flange, cfg, v)
    rot_f, pos_f = rot_f[c], pos_f[c, :, 0]
    n = model.tool.n_markers
    rot_b, p_b = np.eye(3), y.mean(axis=0) - pos_f.mean(axis=0)
    for _ in range(iterations):
        local = np.einsum("kji,kj->ki", rot_f, (y - p_b) @ rot_b - pos_f)
        u = np.array([local[j == i].mean(axis=0) for i in range(n)])
        pred = pos_f + np.einsum("kij,kj->ki", rot_f, u[j])
        rot_b, p_b = register(pred, y)
    spread = np.sqrt(np.mean(np.sum((local - u[j]) ** 2, axis=1))) * 1000.0
    rms = np.sqrt(np.mean((y - pred @ rot_b.T - p_b) ** 2)) * 1000.0
    return RoughStart(u, rot_b, p_b, float(spread), float(rms))


def start_parameters(model, measurements):
    """Nominal parameter set with markers and base from :func:`rough_start`."""
    from doe_calib.model.rotations import matrix_to_rotation_vector

    rs = rough_start(model, measurements)
    params = model.nominal()
    v = params.values.copy()
    v[params.index("markers")] = rs.markers.ravel()
    v[params.index("base")] = np.concatenate([rs.translation,
                                              matrix_to_rotation_vector(rs.rotation)])
    return params.with_values(v)
