"""Identification against simulated truth: exact recovery, Monte Carlo, held-out prediction."""
import warnings

import numpy as np
import pytest

from doe_calib import (
    Configurations,
    DataError,
    FitSettings,
    IdentifiabilityWarning,
    Tool,
    build_model,
    examples,
    identify,
    marker_positions,
    point_covariance,
    predict_covariance,
    simulate,
)
from doe_calib.estimation.preparation import fix_unidentifiable, register_base
from doe_calib.model.evaluation import evaluate
from doe_calib.model.loads import unloaded_and_loaded
from doe_calib.model.simulate import random_configurations, random_truth

MC_REPETITIONS = 800


def _loaded_design(robot, m, rng, mass=250.0, com=(0.0, 0.1, 0.3)):
    """m random poses, each unloaded and with a 250 kg mass hanging from the flange."""
    model = build_model(robot, Tool.from_yaml(examples.TOOL_YAML), "")
    q = random_configurations(robot, m, rng)
    return unloaded_and_loaded(model, model.nominal().values, q, mass, com)


def _identifiable_truth(model, cfg, rng):
    """Random truth whose unidentifiable parameters sit at nominal (the data cannot tell them).

    Identifiability is judged as :func:`identify` judges it: at the registered
    nominal parameters.
    """
    truth = model.nominal().with_values(random_truth(model, rng))
    sim = simulate(model, truth, cfg, 0.0, rng)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        analysed, *_ = fix_unidentifiable(model, sim, register_base(model, sim, model.nominal()))
    v = truth.values.copy()
    v[~analysed.free] = truth.nominal_values[~analysed.free]
    return analysed.with_values(v)


@pytest.fixture(scope="module")
def loaded_design(robot6):
    return _loaded_design(robot6, 40, np.random.default_rng(7))


def test_exact_recovery_noise_free(model6, loaded_design):
    """6R, arbitrary tracker frame, geometry + compliance: recovered to round-off."""
    rng = np.random.default_rng(11)
    truth = _identifiable_truth(model6, loaded_design, rng)
    meas = simulate(model6, truth, loaded_design, 0.0, rng)
    with pytest.warns(IdentifiabilityWarning):
        res = identify(model6, meas)
    assert np.array_equal(res.parameters.free, truth.free)
    err = np.abs(res.parameters.values - truth.values)
    lengths_angles = np.array([p.unit in ("m", "rad") for p in model6.parameters])
    assert err[lengths_angles].max() < 1e-9
    assert err[~lengths_angles].max() < 1e-13  # compliances ~1e-6 rad/(N·m)
    assert res.residuals["rms_mm"] < 1e-8
    assert res.convergence["converged"]


def test_identifiability_explained_in_words(model6, loaded_design):
    rng = np.random.default_rng(3)
    meas = simulate(model6, random_truth(model6, rng), loaded_design, 2e-5, rng)
    with pytest.warns(IdentifiabilityWarning) as record:
        res = identify(model6, meas)
    why = dict(zip(res.parameters.names, res.parameters.fixed_reason))
    assert not res.parameters.free[res.parameters.index("dq_a1")[0]]
    assert "base rotation" in why["dq_a1"]  # joint 1 turns about the tracker's view of the base
    assert "not separable" in str(record[0].message) and len(str(record[0].message)) < 300
    assert all(res.parameters.free[res.parameters.index(["base", "markers"])])


def test_compliance_without_load_is_reported(robot6, tool6):
    model = build_model(robot6, tool6, "joint_offset+joint_compliance")
    rng = np.random.default_rng(5)
    cfg = Configurations.from_arrays(random_configurations(robot6, 20, rng))
    meas = simulate(model, random_truth(model, rng), cfg, 1e-5, rng)
    with pytest.warns(IdentifiabilityWarning):
        res = identify(model, meas)
    why = dict(zip(res.parameters.names, res.parameters.fixed_reason))
    assert "no load in these configurations puts a torque" in why["k_a3"]


def test_fewer_observations_than_unknowns(model6, robot6):
    rng = np.random.default_rng(2)
    cfg = Configurations.from_arrays(random_configurations(robot6, 2, rng))
    meas = simulate(model6, model6.nominal(), cfg, 1e-5, rng)
    params = model6.nominal()
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        with pytest.raises(DataError, match="observed coordinates for .* unknown"):
            identify(model6, meas, params.freed(params.names))


def test_monte_carlo_matches_predicted_covariance(robot6, tool6):
    """Std of MC_REPETITIONS noisy identifications within 10 % of σ²(BᵀB)⁻¹ for every parameter."""
    model = build_model(robot6, tool6, "joint_offset+geometry+joint_compliance")
    rng = np.random.default_rng(21)
    cfg = _loaded_design(robot6, 12, rng)
    truth = _identifiable_truth(model, cfg, rng)
    sigma = 2e-5
    prediction = predict_covariance(model, truth, cfg, sigma)
    predicted = prediction.std()[truth.free]
    # TCP 200 mm in front of the flange at 5 unseen loaded configurations, robot frame
    tcp = np.array([0.0, 0.0, 0.2])
    unseen = _loaded_design(robot6, 5, rng)
    tcp_cov = point_covariance(model, truth, prediction.covariance, unseen, tcp)
    draws, tcps = [], []
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        for _ in range(MC_REPETITIONS):
            res = identify(model, simulate(model, truth, cfg, sigma, rng), truth,
                           settings=FitSettings(register=False))
            draws.append(res.parameters.values[truth.free])
            tcps.append(evaluate(model.point_robot, unseen, res.parameters.values, tcp)[0])
    draws = np.array(draws)
    ratio = draws.std(axis=0) / predicted
    assert np.all(np.abs(ratio - 1) < 0.10), ratio
    bias = (draws.mean(axis=0) - truth.values[truth.free]) / predicted
    assert np.all(np.abs(bias) < 4 / np.sqrt(len(draws)) * 1.5)
    tcp_ratio = np.array(tcps)[..., 0].std(axis=0) / np.sqrt(np.einsum("mii->mi", tcp_cov))
    assert np.all(np.abs(tcp_ratio - 1) < 0.10), tcp_ratio


def test_estimators_agree_and_pose_is_less_precise(model6, loaded_design):
    rng = np.random.default_rng(9)
    truth = _identifiable_truth(model6, loaded_design, rng)
    meas = simulate(model6, truth, loaded_design, 2e-5, rng)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        point = identify(model6, meas, estimator="point")
        two = identify(model6, meas, estimator="two-step")
    f = point.parameters.free
    assert np.allclose(two.parameters.values[f], point.parameters.values[f], atol=1e-9)
    assert two.convergence["converged"]


def test_pose_estimator_is_never_more_precise(model6, loaded_design):
    """Same unknowns (markers known): by Gauss–Markov, point std ≤ pose std for each parameter."""
    rng = np.random.default_rng(9)
    truth = _identifiable_truth(model6, loaded_design, rng)
    known = ~truth.free
    known[truth.index("markers")] = True  # the tool is known exactly here
    truth = truth.with_values(np.where(known, truth.nominal_values, truth.values))
    start = model6.nominal().fixed(["markers"])
    meas = simulate(model6, truth.values, loaded_design, 2e-5, rng)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        point = identify(model6, meas, start, estimator="point")
        pose = identify(model6, meas, start, estimator="pose")
    assert np.array_equal(point.parameters.free, pose.parameters.free)
    f = point.parameters.free
    pose_std, point_std = pose.std(apriori=True), point.std(apriori=True)
    assert np.all(pose_std[f] >= point_std[f] * (1 - 1e-6))
    assert np.all(np.abs(pose.parameters.values[f] - truth.values[f]) < 6 * pose_std[f])


def test_held_out_prediction_reaches_true_model_accuracy(model6, robot6):
    """identify → predict on unseen poses: error within 1.2× of the true model's."""
    rng = np.random.default_rng(31)
    train, test = _loaded_design(robot6, 40, rng), _loaded_design(robot6, 30, rng)
    truth = model6.nominal().with_values(random_truth(model6, rng))  # errors everywhere
    sigma = 2e-5
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        res = identify(model6, simulate(model6, truth, train, sigma, rng))
    held = simulate(model6, truth, test, sigma, rng)
    measured = held.xyz
    predicted = marker_positions(model6, res.parameters.values, test)[held.config, held.marker]
    ideal = marker_positions(model6, truth.values, test)[held.config, held.marker]
    rms_model = np.sqrt(np.mean((measured - predicted) ** 2))
    rms_truth = np.sqrt(np.mean((measured - ideal) ** 2))
    assert rms_model < 1.2 * rms_truth


def test_rounding_only_column_is_not_identifiable(robot6, tool6):
    """A load along joint 6's axis gives it no torque: k_a6's column is rounding noise only."""
    model = build_model(robot6, tool6, "joint_compliance")
    rng = np.random.default_rng(8)
    q = random_configurations(robot6, 15, rng)
    from doe_calib.model.evaluation import evaluate

    rot, _ = evaluate(model.flange, Configurations.from_arrays(q), model.nominal().values)
    axis6 = rot[:, :, 2]  # tool0 z is the a6 axis direction (up to sign)
    w = np.zeros((30, 6))
    # force along the a6 axis through the flange origin (on that axis), plus rounding-level
    # moments: k_a6's column holds only rounding noise
    w[1::2, :3] = 3000.0 * axis6
    w[1::2, 3:] = 1e-10 * rng.normal(size=(15, 3))
    cfg = Configurations.from_arrays(np.repeat(q, 2, axis=0), w, pose=np.repeat(np.arange(15), 2))
    meas = simulate(model, model.nominal().updated(k_a2=5e-7), cfg, 1e-5, rng)
    with pytest.warns(IdentifiabilityWarning):
        res = identify(model, meas)
    assert not res.parameters.free[res.parameters.index("k_a6")[0]]
    assert "no effect" in dict(zip(res.parameters.names, res.parameters.fixed_reason))["k_a6"]
