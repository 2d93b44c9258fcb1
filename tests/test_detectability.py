"""Detectability (design/discovery/detection.py) against Monte Carlo on independently simulated
data, and the words when an effect cannot be seen."""
import warnings

import numpy as np
import pytest
from scipy import stats

from doe_calib import Configurations, Robot, Tool, build_model, examples, identify
from doe_calib.design.detectability import Detectability
from doe_calib.estimation.chi_square import noncentrality_for_power
from doe_calib.design.discovery.detection import design_readings, detect_effects, detectability
from doe_calib.diagnosis.effect_tests import projected_columns
from doe_calib.estimation.preparation import fix_unidentifiable
from doe_calib.estimation.weighted_residuals import weighted_residual
from doe_calib.io.csv_files import read_measurements
from doe_calib.model.loads import unloaded_and_loaded
from doe_calib.model.simulate import random_configurations

import independent_sim as sim

MODEL = "joint_offset+geometry+joint_compliance"
SIGMA_MM = 0.03


def _design(model, m, rng, mass=250.0):
    q = random_configurations(model.robot, m, rng)
    return unloaded_and_loaded(model, model.nominal().values, q, mass, (0.0, 0.1, 0.2))


def _free(model, meas):
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        return fix_unidentifiable(model, meas, model.nominal())[0]


def test_noncentrality_gives_the_stated_power():
    for dof in (1, 2, 3, 6):
        lam = noncentrality_for_power(dof, 0.05, 0.8)
        assert stats.ncx2.sf(stats.chi2.isf(0.05, dof), dof, lam) == pytest.approx(0.8, abs=1e-8)
    assert noncentrality_for_power(1, 0.05, 0.8) == pytest.approx((1.959964 + 0.841621) ** 2,
                                                                  rel=1e-5)


def test_a_cyclic_error_at_its_min_detectable_size_is_detected_at_the_stated_power(tmp_path):
    """Design-time detectability of cyclic(j3) on the KR 270, then an independently simulated
    robot with that cyclic error at min_detectable in the least favourable direction: the score
    test on the fitted residual detects it in 80 % ± 7 % of 400 noise replicates."""
    robot, tool = Robot.from_urdf(examples.ROBOT_URDF), Tool.from_yaml(examples.TOOL_YAML)
    model = build_model(robot, tool, MODEL)
    rng = np.random.default_rng(8)
    cfg = _design(model, 20, rng)
    planned = design_readings(model, model.nominal().values, cfg, SIGMA_MM / 1000)
    (det,) = detectability(model, _free(model, planned), planned,
                           detect_effects(model, "cyclic(j3)"), alpha=0.05, power=0.8)
    assert det.detectable and det.unit == "deg" and det.parameters == ("cyc_a3_s1", "cyc_a3_c1")
    # the truth, simulated without doe_calib's effect modules: Δq3 = A·sin(q3 + φ)
    s, c = det.direction
    amplitude = np.radians(det.min_detectable)
    chain = sim.Chain.from_urdf(examples.ROBOT_URDF, "tool0")
    truth = sim.Truth.random(chain, tool.position_array, rng,
                             effects=(sim.Cyclic(2, amplitude, 1, float(np.arctan2(c, s))),))
    path = tmp_path / "campaign.csv"
    sim.write_campaign(path, chain, truth, cfg.q, cfg.wrench, tool.names, 0.0, rng,
                       write_sigma=False)
    meas = read_measurements(path, robot, tool, sigma=SIGMA_MM / 1000)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        fit = identify(model, meas)  # noise-free: the misfit is the effect's unabsorbed part
    r0, jac = weighted_residual(model, meas, fit.parameters.values)
    q_model = np.linalg.svd(jac[:, fit.parameters.free], full_matrices=False)[0]
    q_model = q_model[:, : int(fit.parameters.free.sum())]
    (effect,) = detect_effects(model, "cyclic(j3)")
    _, zp = projected_columns(model, meas, fit.parameters, effect, q_model)
    u_effect = np.linalg.svd(zp, full_matrices=False)[0]
    critical = stats.chi2.isf(0.05, zp.shape[1])
    noise = np.random.default_rng(9).normal(size=(400, r0.size))
    # the refit of each noisy campaign, to first order: r = r0 + (I − QQᵀ)ε (ε in σ)
    r = r0 + noise - (noise @ q_model) @ q_model.T
    detected = np.mean(((r @ u_effect) ** 2).sum(axis=1) > critical)
    assert detected == pytest.approx(0.8, abs=0.07), detected


def test_a_vertical_load_cannot_reveal_torque_backlash_of_a1_and_a_horizontal_pull_can():
    robot, tool = Robot.from_urdf(examples.ROBOT_URDF), Tool.from_yaml(examples.TOOL_YAML)
    model = build_model(robot, tool, MODEL)
    rng = np.random.default_rng(4)
    vertical = _design(model, 15, rng)
    planned = design_readings(model, model.nominal().values, vertical, SIGMA_MM / 1000)
    (det,) = detectability(model, _free(model, planned), planned,
                           detect_effects(model, "backlash(j1,mode=torque)"))
    assert not det.detectable and det.min_detectable == np.inf
    assert "torque on joint a1" in det.why
    # the same poses, the loaded ones pulled sideways (1 kN along x, 1 kN along y)
    wrench = vertical.wrench.copy()
    wrench[1::2, :3] += np.array([[1000.0, 0.0, 0.0], [0.0, 1000.0, 0.0]] * (len(wrench) // 4)
                                 + [[1000.0, 0.0, 0.0]] * (len(wrench) // 2 % 2))
    pulled = Configurations.from_arrays(vertical.q, wrench, pose=vertical.pose)
    planned = design_readings(model, model.nominal().values, pulled, SIGMA_MM / 1000)
    (det,) = detectability(model, _free(model, planned), planned,
                           detect_effects(model, "backlash(j1,mode=torque)"))
    assert det.detectable and 0 < det.min_detectable < 0.1 and det.unit == "deg"


def test_an_effect_the_model_absorbs_is_named_with_what_absorbs_it():
    """A gear-ratio error of the last joint, held at one angle, turns the flange by a constant
    ε·q6: the same as moving the markers on the flange. Named, not silent."""
    robot, tool = Robot.from_urdf(examples.ROBOT_URDF), Tool.from_yaml(examples.TOOL_YAML)
    model = build_model(robot, tool, MODEL)
    rng = np.random.default_rng(5)
    q = random_configurations(robot, 15, rng)
    q[:, 5] = np.radians(30.0)  # a6 never moves: its scale error is its offset
    cfg = Configurations.from_arrays(q)
    planned = design_readings(model, model.nominal().values, cfg, SIGMA_MM / 1000)
    (det,) = detectability(model, _free(model, planned), planned,
                           detect_effects(model, "gear_ratio(j6)"))
    assert not det.detectable and "cannot be told apart from" in det.why
    assert "marker_" in det.why  # the tool's marker positions absorb a constant flange turn
    assert det.absorbed == pytest.approx(1.0, abs=1e-6)


def test_catalogue_names_every_candidate_and_round_trips():
    robot, tool = Robot.from_urdf(examples.THREE_DOF_URDF), Tool.from_yaml(
        examples.THREE_DOF_TOOL_YAML)
    model = build_model(robot, tool, "joint_offset+joint_compliance")
    cfg = _design(model, 12, np.random.default_rng(2), mass=50.0)
    planned = design_readings(model, model.nominal().values, cfg, SIGMA_MM / 1000)
    effects = detect_effects(model, "catalogue", cfg)
    out = detectability(model, _free(model, planned), planned, effects)
    assert [d.effect for d in out] == [e.spec() for e in effects] and len(out) > 5
    for d in out:
        assert d.detectable == np.isfinite(d.min_detectable) and (d.detectable or d.why)
        back = Detectability.from_dict(d.to_dict())
        assert back == d or (not d.detectable and back.to_dict() == d.to_dict())


def test_design_detect_through_the_cli(tmp_path, capsys, monkeypatch):
    """`doe-calib design --detect …`: JSON, summary and report say what the poses can reveal;
    the design file reads back (no model built) with the same detectability."""
    import casadi

    import doe_calib
    from doe_calib.cli import main

    out, report = tmp_path / "d.json", tmp_path / "d.html"
    assert main(["design", "--robot", examples.ROBOT_URDF, "--tool", examples.TOOL_YAML,
                 "--model", MODEL, "--poses", "12", "--load", "250@0,0,200",
                 "--candidates", "600", "--no-refine", "--no-collision", "--seed", "3",
                 "--detect", "cyclic(j3)+backlash(j1,mode=torque)", "--out", str(out),
                 "--report", str(report)]) == 0
    text = capsys.readouterr().out
    assert "What these poses can reveal" in text and "torque on joint a1" in text
    made = []
    monkeypatch.setattr(casadi, "Function", lambda *a, **k: made.append(a))
    design = doe_calib.load(out)
    monkeypatch.undo()
    assert made == []
    cyc, bl = design.detectability
    assert cyc.effect == "cyclic(j3,harmonics=1)" and cyc.detectable and cyc.unit == "deg"
    assert not bl.detectable and bl.min_detectable == np.inf
    assert "What these poses can reveal" in report.read_text()
    assert main(["design", "--robot", examples.ROBOT_URDF, "--tool", examples.TOOL_YAML,
                 "--model", MODEL, "--poses", "12", "--candidates", "600", "--no-refine",
                 "--no-collision", "--detect", "cyclic(j3)", "--alpha", "0.9",
                 "--out", str(tmp_path / "e.json")]) == 2
    assert "the power must be above the level (alpha < power)" in capsys.readouterr().err
