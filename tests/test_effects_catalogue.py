"""Catalogue effects beyond the core three: Jacobian, independent truth, recovery, spec strings."""
import warnings

import numpy as np
import pytest

from doe_calib import build_model, identify, simulate
from doe_calib.errors import ModelError
from doe_calib.estimation.preparation import fix_unidentifiable, register_base
from doe_calib.model.effects import parse_model
from doe_calib.model.evaluation import marker_positions, observation_matrix
from doe_calib.model.loads import unloaded_and_loaded
from doe_calib.model.simulate import random_configurations, random_truth

BINNED = "compliance_by_angle(j2,edges_deg=-110;-80;-50;-20)"


def _design(model, m, rng):
    q = random_configurations(model.robot, m, rng)
    return unloaded_and_loaded(model, model.nominal().values, q, 250.0, (0.0, 0.1, 0.3))


def test_binned_compliance_is_the_constant_compliance_of_its_bin(robot6, tool6, rng):
    """Independent truth: within one bin the effect is joint_compliance with k_a2 = χ of its bin."""
    binned = build_model(robot6, tool6, BINNED + "+joint_compliance")
    plain = build_model(robot6, tool6, "joint_compliance")
    cfg = _design(binned, 30, rng)
    chi = np.array([1.1, 0.7, 0.9, 0.5, 1.3]) * 1e-6
    pb = binned.nominal().updated(**{f"chi_a2_{b + 1}": c for b, c in enumerate(chi)},
                                  k_a3=2e-6)
    xb = marker_positions(binned, pb.values, cfg)
    bins = np.digitize(np.degrees(cfg.q[:, 1]), [-110, -80, -50, -20])
    assert len(set(bins)) >= 3
    for b in set(bins):
        rows = np.flatnonzero(bins == b)
        pp = plain.nominal().updated(k_a2=chi[b], k_a3=2e-6)
        xp = marker_positions(plain, pp.values, cfg.subset(rows))
        assert np.abs(xb[rows] - xp).max() < 1e-12
    loaded = np.linalg.norm(cfg.wrench, axis=1) > 0
    assert np.abs(xb[loaded] - marker_positions(binned, binned.nominal().values,
                                                cfg.subset(loaded))).max() > 1e-4


def test_binned_compliance_jacobian_matches_finite_differences(robot6, tool6, rng):
    model = build_model(robot6, tool6, "joint_offset+" + BINNED)
    cfg = _design(model, 6, rng)
    p = model.nominal().with_values(random_truth(model, rng)).values
    _, b = observation_matrix(model, p, cfg)
    cols = model.nominal().index("compliance_by_angle")
    for i in cols:
        h = 1e-7
        dp = np.zeros_like(p)
        dp[i] = h
        fd = (marker_positions(model, p + dp, cfg) - marker_positions(model, p - dp, cfg)) / (2 * h)
        assert np.allclose(b[..., i], fd, atol=1e-8 * max(1.0, np.abs(fd).max()))


def test_binned_compliance_recovered_exactly_from_noise_free_data(robot6, tool6):
    rng = np.random.default_rng(4)
    model = build_model(robot6, tool6, "joint_offset+" + BINNED + "+joint_compliance")
    cfg = _design(model, 50, rng)
    truth = model.nominal().with_values(random_truth(model, rng)).fixed(["k_a1", "k_a2"])
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        sim = simulate(model, truth, cfg, 0.0, rng)
        start, *_ = fix_unidentifiable(model, sim, register_base(model, sim, truth.with_values(
            truth.nominal_values)))
        v = truth.values.copy()
        v[~start.free] = truth.nominal_values[~start.free]
        truth = start.with_values(v)
        meas = simulate(model, truth, cfg, 0.0, rng)
        res = identify(model, meas, start.with_values(truth.nominal_values))
    chi = res.parameters.index("compliance_by_angle")
    assert res.parameters.free[chi].all()
    assert np.allclose(res.parameters.values[chi], truth.values[chi], rtol=1e-7, atol=1e-13)


def test_model_strings_round_trip_and_bad_arguments_are_reported():
    (e,) = parse_model("compliance_by_angle(j2, edges_deg=-110;-80;-50;-20)")
    assert e.spec() == "compliance_by_angle(j2,edges_deg=-110;-80;-50;-20)"
    assert parse_model(e.spec())[0].spec() == e.spec()
    assert parse_model("compliance_by_angle(j3)")[0].spec() == "compliance_by_angle(j3,bins=5)"
    with pytest.raises(ModelError, match="must increase"):
        parse_model("compliance_by_angle(j2,edges_deg=-20;-50)")
    with pytest.raises(ModelError, match="numbers separated by ';'"):
        parse_model("compliance_by_angle(j2,edges_deg=a;b)")
