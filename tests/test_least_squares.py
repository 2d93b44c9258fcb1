"""The streamed Levenberg–Marquardt against numpy's QR and scipy's MINPACK on the same problems."""
import numpy as np
import pytest
from scipy.optimize import least_squares

from doe_calib.estimation.least_squares import levenberg_marquardt, reduce_blocks


@pytest.mark.parametrize("cut", [[100], [1, 2, 3, 50], [7, 14, 21, 28, 35]])
def test_streamed_qr_equals_the_whole_qr(cut):
    rng = np.random.default_rng(len(cut))
    jac, r = rng.normal(size=(100, 6)) * [1, 1e3, 1e-3, 1, 5, 1], rng.normal(size=100)
    bounds = [0] + cut + ([100] if cut[-1] != 100 else [])
    red = reduce_blocks([(jac[a:b], r[a:b]) for a, b in zip(bounds, bounds[1:])], 6)
    assert np.allclose(red.r_factor.T @ red.r_factor, jac.T @ jac, rtol=1e-12, atol=1e-9)
    assert np.allclose(red.r_factor.T @ red.z, jac.T @ r, rtol=1e-10)
    assert red.norm2 == pytest.approx(r @ r, rel=1e-13)
    # the least-squares solution from the factor is numpy's
    step = np.linalg.solve(red.r_factor, -red.z)
    assert np.allclose(step, np.linalg.lstsq(jac, -r, rcond=None)[0], rtol=1e-9)


def _exponentials(x, t):
    return x[0] * np.exp(-x[1] * t) + x[2] * np.exp(-x[3] * t) + x[4]


def test_finds_the_minimum_minpack_finds_on_a_nonlinear_fit():
    rng = np.random.default_rng(3)
    t = np.linspace(0, 8, 4000)
    truth = np.array([3.0, 1.3, -1.2, 0.2, 0.5])
    y = _exponentials(truth, t) + 0.01 * rng.normal(size=t.size)

    def residual(x):
        return _exponentials(x, t) - y

    def jacobian(x):
        e1, e2 = np.exp(-x[1] * t), np.exp(-x[3] * t)
        return np.column_stack([e1, -x[0] * t * e1, e2, -x[2] * t * e2, np.ones_like(t)])

    x0, scale = np.array([1.0, 1.0, -1.0, 0.1, 0.0]), np.ones(5)

    def reduce(x):
        r, j = residual(x), jacobian(x) * scale
        return reduce_blocks(((j[a:a + 500], r[a:a + 500]) for a in range(0, t.size, 500)), 5)

    sol = levenberg_marquardt(lambda x: float(residual(x) @ residual(x)), reduce, x0, scale)
    ref = least_squares(residual, x0, jac=jacobian, method="lm", xtol=1e-12, ftol=1e-12,
                        gtol=1e-12)
    assert sol.converged, sol.message
    # the two agree far inside the estimate's own uncertainty (the cost is flat there)
    j = jacobian(ref.x)
    std = np.sqrt(np.diag(np.linalg.inv(j.T @ j)) * 2 * ref.cost / (t.size - 5))
    assert np.all(np.abs(sol.x - ref.x) < 1e-3 * std)
    assert sol.norm2 <= 2 * ref.cost * (1 + 1e-10)
    assert sol.iterations < 50


def test_out_of_iterations_is_not_called_converged():
    t = np.linspace(0, 8, 200)
    y = _exponentials([3.0, 1.3, -1.2, 0.2, 0.5], t)

    def reduce(x):
        e1, e2 = np.exp(-x[1] * t), np.exp(-x[3] * t)
        j = np.column_stack([e1, -x[0] * t * e1, e2, -x[2] * t * e2, np.ones_like(t)])
        return reduce_blocks([(j, _exponentials(x, t) - y)], 5)

    sol = levenberg_marquardt(lambda x: float(np.sum((_exponentials(x, t) - y) ** 2)), reduce,
                              np.array([1.0, 1.0, -1.0, 0.1, 0.0]), np.ones(5),
                              max_iterations=2)
    assert not sol.converged and sol.status == 0
    assert "iteration limit" in sol.message
