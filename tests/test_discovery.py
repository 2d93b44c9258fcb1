"""Designs that can discover (design/discovery/goal.py): load cases and approach sides chosen so
that listed effects are detectable at a size, checked by detectability on the result and by Monte
Carlo on an independently simulated torque-sign backlash."""
import json
import warnings

import numpy as np
import pytest
from scipy import stats

from doe_calib import Robot, Tool, build_model, examples, identify
from doe_calib.design import LoadCase
from doe_calib.design.solvers.constrained_exchange import constrained_exchange
from doe_calib.design.discovery import DiscoveryGoal
from doe_calib.design.discovery.detection import detect_effects, with_detectability
from doe_calib.design.discovery.load_directions import DirectedLoad, parse_directions
from doe_calib.design.optimal import optimal_design
from doe_calib.diagnosis.effect_tests import projected_columns
from doe_calib.errors import OptionError
from doe_calib.estimation.weighted_residuals import weighted_residual
from doe_calib.io.csv_files import read_measurements
from doe_calib.model.loads import GRAVITY, hanging_mass_wrench
from doe_calib.model.simulate import random_configurations

import independent_sim as sim

MODEL = "joint_offset+geometry+joint_compliance"
SIGMA = 3e-5  # m
BACKLASH = "backlash(j1,mode=torque)"
SIZE = 0.002  # deg: the unconstrained design of these candidates reaches only ~0.004 deg


@pytest.fixture(scope="module")
def kr270():
    robot, tool = Robot.from_urdf(examples.ROBOT_URDF), Tool.from_yaml(examples.TOOL_YAML)
    return build_model(robot, tool, MODEL)


def _design(model, spec, size, directions, seed=3):
    goal = DiscoveryGoal(spec, size, 0.8, 0.05, parse_directions(directions))
    return optimal_design(model, 12, [LoadCase(250.0, (0.0, 0.0, 0.2))], candidates=200,
                          sigma=SIGMA, refine=False, rng=np.random.default_rng(seed),
                          discovery=goal)


def test_a_pull_is_the_weights_force_turned_sideways_at_the_centre_of_mass(kr270):
    q = random_configurations(kr270.robot, 5, np.random.default_rng(0))
    values, com = kr270.nominal().values, (0.05, -0.02, 0.2)
    down = DirectedLoad(250.0, com, (0.0, 0.0, -1.0)).wrench(kr270, values, q)
    np.testing.assert_allclose(down, hanging_mass_wrench(kr270, values, q, 250.0, com),
                               atol=1e-9)
    pull = DirectedLoad(250.0, com, (1.0, 0.0, 0.0)).wrench(kr270, values, q)
    np.testing.assert_allclose(pull[:, :3], [[250.0 * GRAVITY, 0.0, 0.0]] * 5)
    # F = (f, 0, 0) at the centre of mass: moment (c − o) × F = (0, a_z f, −a_y f); the
    # weight's (0, 0, −f) gives (−a_y f, a_x f, 0)
    f = 250.0 * GRAVITY
    np.testing.assert_allclose(pull[:, 3], 0.0, atol=1e-9)
    np.testing.assert_allclose(pull[:, 4], f * _arm_z(kr270, values, q, com), atol=1e-6)
    np.testing.assert_allclose(pull[:, 5], down[:, 3], atol=1e-6)
    assert parse_directions("z,x,y") == ((0, 0, -1), (1, 0, 0), (-1, 0, 0), (0, 1, 0), (0, -1, 0))
    with pytest.raises(OptionError, match="'w' is not one of"):
        parse_directions("z,w")


def _arm_z(model, values, q, com):
    from doe_calib.io.measurements import Configurations
    from doe_calib.model.evaluation import evaluate
    cfg = Configurations.from_arrays(q)
    o = evaluate(model.point_robot, cfg, values, np.zeros(3))[0][:, :, 0]
    c = evaluate(model.point_robot, cfg, values, np.asarray(com))[0][:, :, 0]
    return (c - o)[:, 2]


def test_the_constrained_exchange_meets_the_bound_on_the_projected_information():
    """Random blocks: the bound λ_min(Z⊥ᵀZ⊥) ≥ t holds on the chosen rows, Z⊥ by explicit QR
    projection, and D is lower than the unconstrained exchange's by what the bound costs."""
    rng = np.random.default_rng(1)
    blocks = rng.normal(size=(300, 3, 6))
    z = rng.normal(size=(300, 3, 2)) * np.where(np.arange(300) < 30, 1.0, 0.05)[:, None, None]
    pose = np.arange(300)
    free = constrained_exchange(blocks, [], [], np.arange(10), pose)

    def lam(chosen):
        b, zz = blocks[chosen].reshape(-1, 6), z[chosen].reshape(-1, 2)
        qb = np.linalg.qr(b)[0]
        zp = zz - qb @ (qb.T @ zz)
        return np.linalg.eigvalsh(zp.T @ zp)[0]

    target = 4.0 * lam(free.indices)
    found = constrained_exchange(blocks, [z], [target], free.indices, pose)
    assert lam(found.indices) >= target * (1 - 1e-9) and "met" in found.status
    assert len(set(found.indices.tolist())) == 10
    assert found.value < free.value
    b = blocks[found.indices].reshape(-1, 6)
    assert found.value == pytest.approx(np.linalg.slogdet(b.T @ b)[1])


def test_a_vertical_load_cannot_discover_a1_torque_backlash(kr270):
    d = _design(kr270, BACKLASH, SIZE, "z")
    (det,) = d.detectability
    assert not det.detectable and det.min_detectable == np.inf
    (row,) = d.stages["discovery"]["effects"]
    assert not row["revealable"] and not row["met"] and row["min_detectable"] is None
    words = row["words"]
    assert "no allowed load or approach side reveals it" in words
    assert "torque on joint a1" in words and "--load-directions z,x,y" in words
    assert words in d.summary()
    assert set(d.stages["discovery"]["load_cases_used"]) == {"250@0,0,200 along -z"}


def test_a_horizontal_pull_makes_a1_torque_backlash_detectable_at_the_size_asked(kr270,
                                                                                 tmp_path):
    """Asked 0.002 deg at 80 %: met (detectability recomputed on the design), at a small cost
    in D; then a robot with a torque-sign backlash of 0.002 deg on A1, simulated independently,
    is detected at ≥ 80 % − 7 % over 400 linearised noise replicates."""
    loose = _design(kr270, BACKLASH, 1.0, "z,x")  # a bound every design meets: unconstrained
    assert loose.detectability[0].min_detectable > 1.5 * SIZE
    d = _design(kr270, BACKLASH, SIZE, "z,x")
    (det,) = with_detectability(d, kr270, BACKLASH, 0.05, 0.8).detectability
    assert det.detectable and det.min_detectable <= SIZE * (1 + 1e-6)
    (row,) = d.stages["discovery"]["effects"]
    assert row["met"] and row["revealable"] and row["min_detectable"] == det.min_detectable
    pulls = [s for s in d.stages["discovery"]["load_cases_used"] if "along -z" not in s]
    assert pulls  # the design chose sideways pulls
    # its D-efficiency against the unconstrained choice: reported, true, and only slightly below
    versus = d.stages["discovery"]["d_efficiency_vs_unconstrained"]
    p = len(d.predicted_std)
    assert d.stages["discovery"]["unconstrained_log_det"] == pytest.approx(loose.value)
    assert versus == pytest.approx(np.exp((d.value - loose.value) / p), rel=1e-9)
    assert 0.9 <= versus < 1.0 and f"D-efficiency {versus:.3f}" in d.summary()
    # Monte Carlo on an independently simulated backlash of width SIZE
    robot, tool = kr270.robot, kr270.tool
    cfg = d.configurations
    rng = np.random.default_rng(11)
    chain = sim.Chain.from_urdf(examples.ROBOT_URDF, "tool0")
    truth = sim.Truth.random(chain, tool.position_array, rng,
                             effects=(sim.TorqueSignBacklash(0, np.radians(SIZE)),))
    path = tmp_path / "campaign.csv"
    sim.write_campaign(path, chain, truth, cfg.q, cfg.wrench, tool.names, 0.0, rng,
                       write_sigma=False)
    meas = read_measurements(path, robot, tool, sigma=SIGMA)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        fit = identify(kr270, meas)  # noise-free: the misfit is the backlash's unabsorbed part
    r0, jac = weighted_residual(kr270, meas, fit.parameters.values)
    q_model = np.linalg.svd(jac[:, fit.parameters.free], full_matrices=False)[0]
    q_model = q_model[:, : int(fit.parameters.free.sum())]
    (effect,) = detect_effects(kr270, BACKLASH)
    _, zp = projected_columns(kr270, meas, fit.parameters, effect, q_model)
    u_effect = np.linalg.svd(zp, full_matrices=False)[0]
    critical = stats.chi2.isf(0.05, zp.shape[1])
    noise = np.random.default_rng(12).normal(size=(400, r0.size))
    r = r0 + noise - (noise @ q_model) @ q_model.T
    detected = np.mean(((r @ u_effect) ** 2).sum(axis=1) > critical)
    assert detected >= 0.8 - 0.07, detected


def test_a_size_out_of_reach_reports_the_best_size_reached(kr270):
    d = _design(kr270, BACKLASH, 0.0005, "z,x")
    (row,) = d.stages["discovery"]["effects"]
    (det,) = with_detectability(d, kr270, BACKLASH, 0.05, 0.8).detectability
    assert row["revealable"] and not row["met"] and "cannot all be met" in \
        d.stages["discovery"]["status"]
    assert 0.0005 < det.min_detectable < 0.002  # closer than the unconstrained ~0.004 deg
    assert row["min_detectable"] == det.min_detectable
    assert f"best size reachable: {det.min_detectable:.3g} deg" in row["words"]


def test_approach_sides_become_design_variables(kr270):
    d = _design(kr270, "backlash(j2,mode=approach)", 0.002, "z")
    sides = {int(a) for a in d.configurations.approach[:, 1]}
    assert sides == {1, -1}  # both sides planned for a2
    assert not d.configurations.approach[:, [0, 2, 3, 4, 5]].any()
    assert d.stages["discovery"]["approach_joints"] == ["a2"]
    (det,) = d.detectability
    assert det.detectable and d.stages["discovery"]["effects"][0]["met"]
    assert det.min_detectable <= 0.002 * (1 + 1e-6)


def test_discovery_through_the_cli(tmp_path, capsys):
    from doe_calib.cli import main

    out = tmp_path / "d.json"
    args = ["design", "--robot", examples.ROBOT_URDF, "--tool", examples.TOOL_YAML,
            "--model", MODEL, "--poses", "12", "--load", "250@0,0,200", "--candidates", "150",
            "--no-refine", "--no-collision", "--seed", "3", "--sigma", "0.03"]
    assert main(args + ["--detect", BACKLASH, "--detect-size", "0.003", "--min-power", "0.8",
                        "--load-directions", "z,x", "--out", str(out)]) == 0
    text = capsys.readouterr().out
    assert "discovery design (constrained exchange)" in text
    saved = json.loads(out.read_text())
    (row,) = saved["stages"]["discovery"]["effects"]
    assert row["effect"] == BACKLASH and row["revealable"]
    assert saved["detectability"][0]["effect"] == BACKLASH
    assert main(args + ["--load-directions", "z,x", "--out", str(tmp_path / "e.json")]) == 2
    assert "give --detect EFFECTS --detect-size S too" in capsys.readouterr().err
    assert main(args + ["--detect", BACKLASH, "--detect-size", "0.003", "--criterion", "A",
                        "--out", str(tmp_path / "f.json")]) == 2
    assert "maximise the D criterion" in capsys.readouterr().err
