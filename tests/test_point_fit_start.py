"""The point estimator's first Jacobian pass, taken from the rank analysis' reduction,
equals one taken from the data, and the fit is the same with one pass over the data less."""
import warnings

import numpy as np

from doe_calib import simulate
from doe_calib.estimation import weighted_residuals
from doe_calib.estimation.least_squares import restrict
from doe_calib.estimation.point_fit import point_fit
from doe_calib.estimation.preparation import prepare
from doe_calib.model.loads import unloaded_and_loaded
from doe_calib.model.simulate import random_configurations, random_truth


def _campaign(model, rng, m=40):
    q = random_configurations(model.robot, m, rng)
    cfg = unloaded_and_loaded(model, model.nominal().values, q, 250.0, (0.0, 0.1, 0.3))
    return simulate(model, random_truth(model, rng), cfg, 2e-5, rng)


def _counted(monkeypatch):
    calls = []
    real = weighted_residuals.reduce_jacobian

    def counting(*args, **kwargs):
        calls.append(1)
        return real(*args, **kwargs)

    monkeypatch.setattr("doe_calib.estimation.point_fit.reduce_jacobian", counting)
    return calls


def test_restricted_reduction_is_the_data_s(model6, rng):
    meas = _campaign(model6, rng)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        params, _, full, _ = prepare(model6, meas)
    free, scale = params.free, params.scales[params.free]
    got = restrict(full, np.flatnonzero(free), scale)
    want = weighted_residuals.reduce_jacobian(model6, meas, params.values, free, scale)
    # R is unique up to the sign of each row: compare RᵀR, Rᵀz and the norms
    assert np.allclose(got.r_factor.T @ got.r_factor, want.r_factor.T @ want.r_factor,
                       rtol=1e-10, atol=1e-8 * np.abs(want.r_factor).max() ** 2)
    assert np.allclose(got.r_factor.T @ got.z, want.r_factor.T @ want.z, rtol=1e-10,
                       atol=1e-9 * np.abs(want.r_factor.T @ want.z).max())
    assert abs(got.norm2 / want.norm2 - 1) < 1e-12


def test_fit_from_the_rank_analysis_saves_a_pass(model6, rng, monkeypatch):
    meas = _campaign(model6, rng)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        params, _, full, _ = prepare(model6, meas)
    calls = _counted(monkeypatch)
    plain = point_fit(model6, meas, params)
    n_plain = len(calls)
    calls.clear()
    started = point_fit(model6, meas, params, start=full)
    assert len(calls) == n_plain - 1
    assert started.iterations == plain.iterations
    scale = params.scales[params.free]
    assert np.allclose(started.x / scale, plain.x / scale, rtol=0, atol=1e-9)
    assert abs(started.norm2 / plain.norm2 - 1) < 1e-10
