"""The refine fast paths against the reference ones (issue 22).

A repeated evaluation returns the buffers of the last call (the same bits as evaluating
again), and the detection power's noncentrality comes from cdflib's inverse instead of a
root search (the same λ to 1e-12).
"""
import numpy as np
import pytest
from scipy import optimize, stats

from doe_calib import Configurations
from doe_calib.design.detectability import noncentrality_for_power
from doe_calib.model.evaluation import Workspace, observation_matrix
from doe_calib.model.simulate import random_configurations, random_truth


@pytest.mark.parametrize("dof", [1, 2, 3, 5, 8, 13, 40, 120])
@pytest.mark.parametrize("alpha, power", [(0.05, 0.8), (0.01, 0.9), (0.001, 0.5)])
def test_noncentrality_is_the_root_of_the_power_equation(dof, alpha, power):
    critical = stats.chi2.isf(alpha, dof)
    truth = optimize.brentq(lambda lam: stats.ncx2.sf(critical, dof, lam) - power, 1e-9, 1e4,
                            xtol=1e-13, rtol=1e-14)
    assert noncentrality_for_power(dof, alpha, power) == pytest.approx(truth, rel=1e-10)


def test_power_at_or_below_the_level_needs_no_signal():
    assert noncentrality_for_power(3, 0.05, 0.05) == 0.0


def _campaign(model, seed, n=7):
    rng = np.random.default_rng(seed)
    q = random_configurations(model.robot, n, rng)
    w = rng.normal(scale=[300, 300, 300, 50, 50, 50], size=(n, 6))
    return Configurations.from_arrays(q, w), random_truth(model, rng)


def test_a_repeated_evaluation_is_the_evaluation(model6):
    cfg, values = _campaign(model6, 1)
    other_cfg, other = _campaign(model6, 2)
    ws = Workspace()
    first = observation_matrix(model6, values, cfg, workspace=ws)
    again = observation_matrix(model6, values, cfg, workspace=ws)  # from the buffers
    for a, b in zip(first, again):
        assert np.array_equal(a, b)
        a[...] = 0.0  # the caller owns what it was given: the buffers are not touched
    # a changed value, in place or not, is evaluated afresh, and equals a fresh workspace's
    moved = values.copy()
    moved[7] += 1e-9
    for vals, c in ((moved, cfg), (other, cfg), (values, other_cfg), (values, cfg)):
        got = observation_matrix(model6, vals, c, workspace=ws)
        fresh = observation_matrix(model6, vals, c, workspace=Workspace())
        for a, b in zip(got, fresh):
            assert np.array_equal(a, b)
    assert np.any(observation_matrix(model6, moved, cfg, workspace=ws)[1]
                  != observation_matrix(model6, values, cfg, workspace=ws)[1])


def test_the_first_call_is_evaluated_even_at_zero(model6):
    """The buffers start at zero: a first call with zero inputs is still evaluated."""
    cfg = Configurations.from_arrays(np.zeros((3, 6)), np.zeros((3, 6)))
    zero = np.zeros(model6.n_parameters)
    got = observation_matrix(model6, zero, cfg, workspace=Workspace())
    x_single = np.array(model6.observation(np.zeros(6), np.zeros(6),
                                           np.zeros(model6.observation.size1_in(2)),
                                           zero)[0]).ravel()
    assert np.abs(got[0][0].ravel()).max() > 0  # the tool's markers are off the flange
    assert np.array_equal(got[0][0].ravel(), x_single)
