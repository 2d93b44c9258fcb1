"""Parameter selection on few data (doe_calib.estimation.selection), on campaigns doe_calib
did not simulate (``independent_sim``): its predicted error at new poses is the true
leave-one-pose-out error, it keeps every parameter of a rich campaign, and on few poses
with unmodelled effects it predicts new poses no worse than the whole fit."""
import warnings
from dataclasses import replace

import independent_sim as sim
import numpy as np
import pytest
from markered_robot import markered_robot

from doe_calib import build_model, examples
from doe_calib.diagnosis import validation_rms
from doe_calib.estimation.identify import FitSettings, identify
from doe_calib.estimation.result import IdentificationResult
from doe_calib.estimation.selection import REASON, pose_groups, propose
from doe_calib.io.csv_files import read_measurements

SMR = {"A": [0.12, 0.05, 0.10]}
SIGMA_MM = 0.02


@pytest.fixture(scope="module")
def kr270():
    chain, robot, tool = markered_robot(examples.ROBOT_URDF, "tool0", SMR)
    return chain, robot, tool, build_model(robot, tool, "joint_offset+geometry")


def _campaign(tmp_path, kr270, seed, n, amplitude_deg, n_valid=0):
    """n training poses (and n_valid new ones) of one reflector; the truth has placement
    errors and two cyclic joint errors the model does not hold (amplitude_deg)."""
    chain, robot, tool, _ = kr270
    rng = np.random.default_rng(seed)
    hidden = (sim.Cyclic(1, np.radians(amplitude_deg), 2, 0.3),
              sim.Cyclic(2, np.radians(amplitude_deg), 1, 1.0))
    truth = sim.Truth.random(chain, np.array(list(SMR.values())), rng, effects=hidden)
    out = []
    for name, m in (("train", n), ("valid", n_valid)):
        if m:
            q = sim.random_configurations(chain, m, rng)
            path = tmp_path / f"{name}_{seed}.csv"
            sim.write_campaign(path, chain, truth, q, np.zeros((m, 6)), list(SMR), SIGMA_MM, rng)
            out.append(read_measurements(path, robot, tool))
    return out


def _fit(model, meas, params=None, **options):
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        return identify(model, meas, params, settings=FitSettings(**options))


def _brute_force_loo_mm(model, meas, params):
    """3-D RMS (mm) of each pose predicted by the fit on the others, refitted (no formula)."""
    pose = np.asarray(meas.configurations.pose)[meas.config]
    sq = []
    for p in dict.fromkeys(pose):
        fit = _fit(model, meas.subset(np.flatnonzero(pose != p)), params, select="none",
                   register=False)
        held = meas.subset(np.flatnonzero(pose == p))
        sq.append(3 * len(held) * validation_rms(model, fit.parameters.values, held) ** 2)
    return float(np.sqrt(np.sum(sq) / len(pose)))


def test_predicted_error_is_the_leave_one_pose_out_error_of_refits(tmp_path, kr270):
    """The hat-matrix formula against one refit per held-out pose, for the fit whole and for
    the fit with the proposed parameter at nominal."""
    model = kr270[3]
    (train,) = _campaign(tmp_path, kr270, seed=1, n=20, amplitude_deg=0.05)
    whole = _fit(model, train, select="none")
    prop = propose(model, train, whole.parameters, pose_groups(train))
    assert prop.name is not None and prop.variance_inflation > 1.0
    assert prop.rms_3d_mm == pytest.approx(_brute_force_loo_mm(model, train, whole.parameters),
                                           rel=0.02)
    i = whole.parameters.position(prop.name)
    v = whole.parameters.values.copy()
    v[i] = whole.parameters.nominal_values[i]
    without = whole.parameters.with_values(v).fixed([prop.name])
    assert prop.rms_without_mm == pytest.approx(_brute_force_loo_mm(model, train, without),
                                                rel=0.02)


def test_a_rich_campaign_keeps_every_parameter(tmp_path, kr270):
    """60 poses of a model of the true form: nothing is left at nominal, the fit is the whole
    one, and the result says the selection ran and kept everything."""
    chain, robot, tool, model = kr270
    rng = np.random.default_rng(7)
    truth = sim.Truth.random(chain, np.array(list(SMR.values())), rng)
    q = sim.random_configurations(chain, 60, rng)
    sim.write_campaign(tmp_path / "rich.csv", chain, truth, q, np.zeros((60, 6)), list(SMR),
                       SIGMA_MM, rng)
    meas = read_measurements(tmp_path / "rich.csv", robot, tool)
    chosen, whole = _fit(model, meas), _fit(model, meas, select="none")
    assert chosen.selection.left_at_nominal == () and whole.selection is None
    assert len(chosen.selection.predicted_rms_3d_mm) == 1
    assert np.array_equal(chosen.parameters.free, whole.parameters.free)
    np.testing.assert_allclose(chosen.parameters.values, whole.parameters.values, atol=1e-12)
    assert "every parameter kept" in chosen.fit_report()


def test_many_poses_per_parameter_skip_the_selection(tmp_path, kr270):
    """Ten poses per free parameter or more: the selection is not run, and the result says so."""
    chain, robot, tool, _ = kr270
    model = build_model(robot, tool, "joint_offset")
    rng = np.random.default_rng(3)
    truth = sim.Truth.random(chain, np.array(list(SMR.values())), rng)
    q = sim.random_configurations(chain, 150, rng)
    sim.write_campaign(tmp_path / "many.csv", chain, truth, q, np.zeros((150, 6)), list(SMR),
                       SIGMA_MM, rng)
    res = _fit(model, read_measurements(tmp_path / "many.csv", robot, tool))
    # base 6, marker 3, four offsets (a1's goes with the base, a6's with the reflector)
    assert res.parameters.free.sum() == 13
    assert res.selection.predicted_rms_3d_mm == () and res.selection.left_at_nominal == ()
    assert "parameter selection not run: 150 poses for 13 free parameters" in res.fit_report()


def test_few_poses_with_unmodelled_effects_predict_new_poses_no_worse(tmp_path, kr270):
    """Twenty poses for 27 separable parameters, two cyclic joint errors the model lacks: over
    eight campaigns the selected fit predicts 40 new poses (independent truth) better on
    average than the whole fit and never much worse, and each result says what it left out."""
    model = kr270[3]
    ratios, left = [], 0
    for seed in range(8):
        train, valid = _campaign(tmp_path, kr270, seed, n=20, amplitude_deg=0.05, n_valid=40)
        chosen, whole = _fit(model, train), _fit(model, train, select="none")
        ratios.append(validation_rms(model, chosen.parameters.values, valid)
                      / validation_rms(model, whole.parameters.values, valid))
        sel = chosen.selection
        left += len(sel.left_at_nominal)
        assert len(sel.predicted_rms_3d_mm) == len(sel.left_at_nominal) + 1
        assert all(b < a for a, b in zip(sel.predicted_rms_3d_mm, sel.predicted_rms_3d_mm[1:]))
        for name in sel.left_at_nominal:
            est = chosen[name]
            assert not est.free and est.value == est.nominal and est.fixed_reason == REASON
    assert left >= 5, ratios
    assert np.mean(ratios) < 0.995 and max(ratios) < 1.05, ratios


def test_the_selection_is_told_in_the_report_and_survives_json(tmp_path, kr270):
    model = kr270[3]
    (train,) = _campaign(tmp_path, kr270, seed=1, n=20, amplitude_deg=0.05)
    res = _fit(model, train)
    sel = res.selection
    assert sel.left_at_nominal, sel
    assert any("cannot see" in w for w in res.warnings)  # the whole fit's words, carried
    report = res.fit_report()
    assert f"{len(sel.left_at_nominal)} left at nominal" in report
    assert f"fixed as {REASON.split(' (')[0]}" in report
    res.to_json(tmp_path / "r.json")
    back = IdentificationResult.from_json(tmp_path / "r.json")
    assert back.selection == sel
    assert {f["name"] for f in back.to_dict()["fixed"] if f["reason"] == REASON} == \
        set(sel.left_at_nominal)


def test_the_kept_fit_names_the_values_of_the_reduced_set(tmp_path, kr270):
    """A refit with parameters left at nominal still says which values absorb the parameters
    the data cannot separate (the rank analysis of the whole fit) and their combinations."""
    model = kr270[3]
    (train,) = _campaign(tmp_path, kr270, seed=1, n=20, amplitude_deg=0.05)
    res = _fit(model, train)
    whole = _fit(model, train, select="none")
    assert res.selection.left_at_nominal
    kept = {n for n in whole.absorbed if n in res.free_names}
    assert kept and {c.parameter for c in res.combinations()} == kept
    assert all(res[n].role == "reduced set" for n in kept)


def test_a_kept_refit_with_sigma_estimated_states_one_sigma(tmp_path, kr270):
    """The refit's σ̂ is the σ the result uses; the whole fit's σ̂ is not told beside it."""
    model = kr270[3]
    (train,) = _campaign(tmp_path, kr270, seed=1, n=20, amplitude_deg=0.05)
    unknown = replace(train, sigma=np.full(len(train), np.nan), sigma_estimated=True)
    res = _fit(model, unknown)
    assert res.selection.left_at_nominal and res.sigma_estimated
    said = [w for w in res.warnings if w.startswith("σ estimated from the residuals:")]
    assert said == [f"σ estimated from the residuals: {res.sigma_mm:.3g} mm"]
