"""Diagnosis on simulated data with a hidden effect: it ranks first, and adding it brings the
validation RMS to what the true model reaches; a correct model is judged adequate; an effect
outside the catalogue is reported with the variable it follows."""
import warnings

import numpy as np
import pytest

from doe_calib import Configurations, build_model, identify, simulate
from doe_calib.diagnosis import diagnose, validation_rms
from doe_calib.diagnosis.refine import refine
from doe_calib.model.loads import hanging_mass_wrench
from doe_calib.model.simulate import random_configurations, random_truth

SIGMA = 3e-5  # m

# (hidden effect, joint it sits on or None, model that lacks it)
CASES = [
    ("joint_offset", None, "joint_compliance"),
    ("geometry", None, "joint_offset+joint_compliance"),
    ("joint_compliance", None, "joint_offset"),
    ("compliance_by_angle(j2,bins=3)", 2, "joint_offset+joint_compliance"),
    ("gear_ratio(j3)", 3, "joint_offset+joint_compliance"),
    ("cyclic(j4,harmonics=2)", 4, "joint_offset+joint_compliance"),
    ("backlash(j2)", 2, "joint_offset+joint_compliance"),
    ("thermal", None, "joint_offset+joint_compliance"),
    ("link_compliance", None, "joint_offset+joint_compliance"),
]


def _campaign(model, truth, robot, n, rng, drift=0.0):
    """n poses, each unloaded and under ±250 kg-force pulls, temperatures 15–35 °C."""
    q = np.repeat(random_configurations(robot, n, rng), 3, axis=0)
    w = np.zeros((3 * n, 6))
    w[1::3] = hanging_mass_wrench(model, truth, q[1::3], 250.0, (0.0, 0.0, 0.2))
    w[2::3] = -w[1::3]
    temp = np.repeat(rng.uniform(15, 35, n), 3)[:, None]
    cfg = Configurations.from_arrays(q, w, temp, pose=np.repeat(np.arange(n) + 1, 3))
    meas = simulate(model, truth, cfg, SIGMA, rng)
    if drift:  # the tracker drifts with time: outside every catalogue effect
        order = meas.config / len(cfg)
        meas.xyz[:] += drift * order[:, None] * np.array([1.0, -0.5, 0.3])
    return meas


def _fit(model, meas):
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        return identify(model, meas)


@pytest.mark.parametrize("hidden,joint,start", CASES, ids=[c[0] for c in CASES])
def test_hidden_effect_ranks_first_and_adding_it_reaches_the_true_accuracy(
        robot6, tool6, hidden, joint, start):
    rng = np.random.default_rng(sum(map(ord, hidden)))
    true = build_model(robot6, tool6, f"{start}+{hidden}")
    truth = random_truth(true, rng)
    train = _campaign(true, truth, robot6, 40, rng)
    valid = _campaign(true, truth, robot6, 20, rng)
    model = build_model(robot6, tool6, start)
    d = diagnose(model, train)
    assert not d.adequate
    best = d.candidates[0]
    assert best.effect == hidden.split("(")[0] and best.joint == joint, d.summary()
    assert d.proposed == best.spec
    assert best.p_value < 0.01 and best.cv_rms_mm < d.cv_rms_mm
    grown = build_model(robot6, tool6, f"{start}+{best.spec}")
    got = validation_rms(grown, _fit(grown, train).parameters.values, valid)
    reference = validation_rms(true, _fit(true, train).parameters.values, valid)
    assert got <= 1.2 * reference, (got, reference)


def test_correct_model_is_adequate_and_nothing_is_proposed(robot6, tool6):
    rng = np.random.default_rng(7)
    model = build_model(robot6, tool6, "joint_offset+joint_compliance")
    meas = _campaign(model, random_truth(model, rng), robot6, 40, rng)
    d = diagnose(model, meas)
    assert d.adequate and d.best is None, d.summary()
    assert "adequate" in d.verdict and d.flagged == ()
    assert d.noise_floor_mm == pytest.approx(SIGMA * 1e3)
    assert d.cv_rms_mm == pytest.approx(SIGMA * 1e3, rel=0.15)


def test_effect_outside_the_catalogue_is_named_by_the_variable_it_follows(robot6, tool6):
    rng = np.random.default_rng(11)
    model = build_model(robot6, tool6, "joint_offset+joint_compliance")
    meas = _campaign(model, random_truth(model, rng), robot6, 40, rng, drift=0.002)
    d = diagnose(model, meas)
    assert not d.adequate and d.proposed is None
    assert d.follows[0].variable == "measurement order", d.summary()
    assert "measurement order" in d.verdict and "no catalogue effect improves" in d.verdict


def test_refine_adds_the_missing_effects_until_adequate(robot6, tool6):
    rng = np.random.default_rng(5)
    true = build_model(robot6, tool6, "joint_offset+joint_compliance+cyclic(j3,harmonics=2)")
    truth = random_truth(true, rng)
    train, valid = (_campaign(true, truth, robot6, n, rng) for n in (40, 20))
    out = refine(build_model(robot6, tool6, "joint_offset"), train, valid)
    added = [s.added for s in out.steps]
    assert added == [None, "joint_compliance", "cyclic(j3,harmonics=2)"], out.summary()
    assert out.steps[-1].adequate
    v = [s.validation_rms_mm for s in out.steps]
    assert v[0] > v[1] > v[2] and v[2] < 1.2 * SIGMA * 1e3 * np.sqrt(1.1)


def test_diagnosis_json_round_trip(tmp_path, robot6, tool6):
    from doe_calib.diagnosis import DiagnosisResult

    rng = np.random.default_rng(2)
    true = build_model(robot6, tool6, "joint_offset+gear_ratio(j2)")
    meas = _campaign(true, random_truth(true, rng), robot6, 25, rng)
    d = diagnose(build_model(robot6, tool6, "joint_offset"), meas)
    d.to_json(tmp_path / "d.json")
    back = DiagnosisResult.from_json(tmp_path / "d.json")
    assert back.to_dict() == d.to_dict() and back.summary() == d.summary()
