"""Adequacy that scales with N, and variables that barely vary left out of "what the residual
follows"."""
import numpy as np

from doe_calib import Configurations, build_model, simulate
from doe_calib.diagnosis import diagnose
from doe_calib.diagnosis.variables import configuration_variables
from doe_calib.model.evaluation import evaluate
from doe_calib.model.loads import hanging_mass_wrench
from doe_calib.model.simulate import random_configurations, random_truth

SIGMA = 3e-5  # m, stated


def _stated(meas, sigma):
    return meas.__class__(meas.configurations, meas.config, meas.marker, meas.xyz,
                          np.full(len(meas), sigma), meas.line, meas.source)


def _campaign(robot6, model, n, real_sigma, rng):
    q = np.repeat(random_configurations(robot6, n, rng), 2, axis=0)
    truth = random_truth(model, rng)
    w = np.zeros((2 * n, 6))
    w[1::2] = hanging_mass_wrench(model, truth, q[1::2], 250.0, (0.0, 0.0, 0.2))
    cfg = Configurations.from_arrays(q, w, pose=np.repeat(np.arange(n), 2))
    return _stated(simulate(model, truth, cfg, real_sigma, rng), SIGMA)


def test_a_few_percent_excess_over_sigma_at_large_n_is_not_a_missing_effect(robot6, tool6):
    model = build_model(robot6, tool6, "joint_offset+joint_compliance")
    meas = _campaign(robot6, model, 600, 1.03 * SIGMA, np.random.default_rng(3))
    d = diagnose(model, meas)
    c = d.chi2
    assert c["p_value"] < 1e-3 and not c["chi2_adequate"]  # the χ² test alone rejects …
    lo, hi = c["sigma_ratio_interval"]
    assert lo < 1.03 < hi and 1.0 < lo, c  # … and σ̂/σ is known to be 1.03 ± a little
    assert d.adequate and d.best is None, d.summary()
    assert "within 5% of the noise" in d.verdict


def test_a_sigma_ten_times_too_small_is_not_adequate_and_says_check_sigma(robot6, tool6):
    model = build_model(robot6, tool6, "joint_offset+joint_compliance")
    meas = _campaign(robot6, model, 60, 10 * SIGMA, np.random.default_rng(4))
    d = diagnose(model, meas)
    assert not d.adequate and d.best is None and d.gross_errors == ()
    assert "check σ" in d.verdict, d.verdict
    assert 8 < d.chi2["sigma_ratio"] < 12


def test_a_torque_of_round_off_size_is_not_a_variable(robot6, tool6):
    model = build_model(robot6, tool6, "")
    q = random_configurations(robot6, 30, np.random.default_rng(5))
    cfg = Configurations.from_arrays(q)
    rot, _ = evaluate(model.flange, cfg, model.nominal().values)
    w = np.zeros((30, 6))
    w[:, :3] = -2000.0 * rot[:, :, 2]  # pushing along the a6 axis, through its origin
    names = configuration_variables(robot6, Configurations.from_arrays(q, w))
    assert "tau2 (a2)" in names and "tau6 (a6)" not in names
