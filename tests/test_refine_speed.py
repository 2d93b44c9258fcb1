"""The refine fast paths against the reference ones (issue 22).

A repeated evaluation returns the buffers of the last call (the same bits as evaluating
again); the detection power's noncentrality (estimation/chi_square.py) is
the root of SciPy's power equation; refine takes the same steps as diagnosing each grown model
afresh (to 1e-9).
"""
import warnings

import independent_sim as sim
from markered_robot import markered_robot
import numpy as np
import pytest
from scipy import optimize, stats

from doe_calib import Configurations, build_model, examples
from doe_calib.diagnosis.refine import refine
from doe_calib.diagnosis.candidate_scoring import GROWN
from doe_calib.diagnosis.diagnose import diagnose
from doe_calib.diagnosis.settings import RefineSettings
from doe_calib.model.effects import parse_effect
from doe_calib.estimation.effect_signature import augmented
from doe_calib.errors import DoeCalibWarning
from doe_calib.estimation.identify import identify_quietly
from doe_calib.estimation.chi_square import noncentrality_for_power
from doe_calib.io.csv_files import read_measurements
from doe_calib.model.evaluation import Workspace, observation_matrix
from doe_calib.model.simulate import random_configurations, random_truth

MARKERS = {"A": [0.15, 0.0, 0.08], "B": [-0.075, 0.13, 0.08], "C": [-0.075, -0.13, 0.08]}  # m


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
    again = observation_matrix(model6, values, cfg, workspace=ws)
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


@pytest.fixture(scope="module")
def hidden_campaign(tmp_path_factory):
    """30 poses of the KR 270, unloaded and under 250 kg, from the independent simulator: two
    angle-dependent compliances and a cyclic error (refine adds three effects)."""
    chain, robot, tool = markered_robot(examples.ROBOT_URDF, "tool0", MARKERS)
    rng = np.random.default_rng(2)
    hidden = (sim.SmoothAngleCompliance(1, 1e-6, 4e-7, phase=0.7), sim.Cyclic(2, 2e-5, 2),
              sim.SmoothAngleCompliance(2, 6e-7, 2e-7))
    truth = sim.Truth.random(chain, np.array(list(MARKERS.values())), rng, effects=hidden)
    q, w = sim.unloaded_and_loaded(chain, sim.random_configurations(chain, 30, rng), 250.0,
                                   [0.0, 0.0, 0.2])
    path = tmp_path_factory.mktemp("hidden") / "campaign.csv"
    sim.write_campaign(path, chain, truth, q, w, list(MARKERS), 0.02, rng)
    return build_model(robot, tool, "joint_offset+geometry"), read_measurements(path, robot, tool)


def test_refine_from_one_batch_equals_diagnosing_each_step_afresh(hidden_campaign):
    """The same steps and candidates as diagnosing each grown model with a batch of its own
    and fitting the chosen effect again; every number to 1e-9 (rounding: the effects'
    corrections summed in another order)."""
    start, meas = hidden_campaign
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", DoeCalibWarning)
        fit = identify_quietly(start, meas)
        fast = refine(start, meas, fit=fit, settings=RefineSettings(max_steps=3))
        model, step_fit, slow = start, fit, []
        while True:
            slow.append(diagnose(model, meas, step_fit))
            if len(slow) == 4 or slow[-1].best is None:
                break
            model, begin = augmented(model, step_fit.parameters,
                                     parse_effect(slow[-1].best.spec))
            step_fit = identify_quietly(model, meas, begin, settings=GROWN)
    assert len(fast.steps) == len(slow) == 4  # it grows: the comparison covers grown models
    assert [s.added for s in fast.steps[1:]] == [d.best.spec for d in slow[:-1]]
    for a, d, before in zip(fast.steps, slow, [None] + slow[:-1]):
        assert a.cv_rms_mm == pytest.approx(d.cv_rms_mm, rel=1e-9)
        assert a.rms_mm == pytest.approx(d.rms_mm, rel=1e-9)
        if before is not None:
            assert [f.value for f in a.fitted] == pytest.approx(
                [f.value for f in before.best.sizes], rel=1e-9)
    assert fast.fit.parameters.names == step_fit.parameters.names
    assert np.array_equal(fast.fit.parameters.free, step_fit.parameters.free)
    scale = fast.fit.parameters.scales
    assert np.abs((fast.fit.parameters.values - step_fit.parameters.values) / scale).max() \
        <= 1e-9
    ours, theirs = fast.diagnosis.candidates, slow[-1].candidates
    assert [c.spec for c in ours] == [c.spec for c in theirs]
    for a, b in zip(ours, theirs):
        assert a.log10_p == pytest.approx(b.log10_p, rel=1e-9, abs=1e-9), a.spec
        if b.cv_rms_mm is not None:
            assert a.cv_rms_mm == pytest.approx(b.cv_rms_mm, rel=1e-9), a.spec
