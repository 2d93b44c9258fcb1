"""Blockwise residuals and Jacobian factor equal the whole ones, at any block size."""
import numpy as np
import pytest

from doe_calib import Configurations, build_model, simulate
from doe_calib.estimation.identify import identify_quietly
from doe_calib.estimation.weighted_residuals import (
    reduce_jacobian,
    residual_norm2,
    weighted_residual,
)
from doe_calib.model.simulate import random_configurations, random_truth


@pytest.fixture(scope="module")
def campaign(model6, robot6):
    rng = np.random.default_rng(21)
    q = random_configurations(robot6, 23, rng)
    w = np.zeros((23, 6))
    w[::2, 2] = -1500.0
    cfg = Configurations.from_arrays(q, w)
    truth = random_truth(model6, rng)
    meas = simulate(model6, truth, cfg, 2e-5, rng)
    # shuffle the rows, drop some readings, vary σ: blocks must not rely on file order
    keep = rng.permutation(len(meas))[: len(meas) - 5]
    meas = meas.subset(keep)
    meas = meas.__class__(meas.configurations, meas.config, meas.marker, meas.xyz,
                          rng.uniform(1e-5, 4e-5, len(meas)), meas.line, meas.source)
    return meas, truth


@pytest.mark.parametrize("block", [1, 4, 7, 23, 2048])
def test_blocks_equal_the_whole(model6, campaign, block):
    meas, truth = campaign
    values = truth + 1e-4  # not at the truth: residuals of the model's size
    r, jac = weighted_residual(model6, meas, values)
    assert residual_norm2(model6, meas, values, block=block) == pytest.approx(r @ r, rel=1e-12)
    cols = np.array([0, 4, 9, 20, 30, 40])
    scale = np.linspace(0.5, 2.0, len(cols))
    red = reduce_jacobian(model6, meas, values, cols, scale, block=block)
    js = jac[:, cols] * scale
    assert np.allclose(red.r_factor.T @ red.r_factor, js.T @ js, rtol=1e-10,
                       atol=1e-10 * np.abs(js.T @ js).max())
    assert np.allclose(red.r_factor.T @ red.z, js.T @ r, rtol=1e-9,
                       atol=1e-10 * np.abs(js.T @ r).max())
    assert red.norm2 == pytest.approx(r @ r, rel=1e-12)


def test_covariance_of_the_fit_is_that_of_the_whole_jacobian(model6, campaign):
    """σ²(BᵀB)⁻¹ from the streamed factor equals the pseudo-inverse of the whole normal matrix."""
    meas, _ = campaign
    fit = identify_quietly(build_model(model6.robot, model6.tool, model6.spec), meas)
    free = fit.parameters.free
    _, jac = weighted_residual(model6, meas, fit.parameters.values)
    whole = np.linalg.pinv(jac[:, free].T @ jac[:, free])
    std_fit, std_whole = np.sqrt(np.diag(fit.covariance)), np.sqrt(np.diag(whole))
    assert np.allclose(std_fit, std_whole, rtol=1e-6)
