"""Plane touches and ballbar readings made by the independent simulator (numpy and
Pinocchio only): the commanded q at which a truth's ball centre lies on a plane, and the
length a ballbar reads at a commanded q."""
import independent_sim as sim
import numpy as np


def ball(chain, truth, q):
    """True ball centre (3,), m, at commanded q (N,), unloaded."""
    return sim.marker_positions(chain, truth, q[None], np.zeros((1, 6)))[0, 0]


def touch(chain, truth, point, normal, q, scatter_mm, rng):
    """Commanded q (N,) at which the true ball centre, brought from the planned ``q`` along
    the plane's ``normal``, lies on the plane through ``point`` (m) — off it by a normal
    scatter of ``scatter_mm`` along the normal (damped Gauss–Newton on position from the
    planned q, the way the operator or the probe stops the ball), or None."""
    normal = np.asarray(normal, float)
    start = ball(chain, truth, q)
    target = start - (normal @ (start - point) - rng.normal(scale=scatter_mm * 1e-3)) * normal
    for _ in range(60):
        e = target - ball(chain, truth, q)
        if np.linalg.norm(e) < 1e-12:
            return q
        jac = np.array([(ball(chain, truth, q + h) - ball(chain, truth, q - h)) / 2e-7
                        for h in np.eye(len(q)) * 1e-7]).T
        q = q + jac.T @ np.linalg.solve(jac @ jac.T + 1e-6 * np.eye(3), e)
    return None


def ballbar_length_mm(chain, truth, pivot, q, scatter_mm, rng) -> float:
    """The length (mm) a ballbar from ``pivot`` (m) to the true ball reads at commanded
    ``q``, with a scatter of ``scatter_mm``."""
    return float(1e3 * np.linalg.norm(ball(chain, truth, q) - pivot) +
                 rng.normal(scale=scatter_mm))
