"""``--load-directions`` without ``--detect-size`` (design/discovery/goal.py with no size, and
design/augment.py with ``directions``): each pose picks the one load case it is measured
under for the D criterion; the pulls it picks are the forces and moments computed here with
Pinocchio, they make the compliance of A1 designable and its torque backlash detectable,
which the weight alone does not."""
import json

import numpy as np
import pytest

import independent_sim as sim
from doe_calib import Robot, Tool, build_model, examples, simulate
from doe_calib.design import LoadCase
from doe_calib.design.augment import augment_design
from doe_calib.design.discovery import DiscoveryGoal
from doe_calib.design.discovery.detection import with_detectability
from doe_calib.design.discovery.load_directions import parse_directions
from doe_calib.design.optimal import optimal_design
from doe_calib.design.problem import load_configurations
from doe_calib.estimation.weighted_residuals import weighted_residual
from doe_calib.model.simulate import random_configurations

MODEL = "joint_offset+geometry+joint_compliance"
SIGMA = 3e-5  # m
BACKLASH = "backlash(j1,mode=torque)"
LOAD = LoadCase(250.0, (0.0, 0.0, 0.2))


@pytest.fixture(scope="module")
def kr270():
    robot, tool = Robot.from_urdf(examples.ROBOT_URDF), Tool.from_yaml(examples.TOOL_YAML)
    return build_model(robot, tool, MODEL)


def _design(model, directions):
    goal = DiscoveryGoal(BACKLASH, None, 0.8, 0.05, parse_directions(directions))
    return optimal_design(model, 12, [LOAD], candidates=150, sigma=SIGMA, refine=False,
                          rng=np.random.default_rng(3), discovery=goal)


def _check_pulls(cfg, chain):
    """Every pose unloaded then under one load, that load the weight or a pull of the same
    force at the centre of mass (Pinocchio); returns the directions used."""
    used = set()
    for pose in dict.fromkeys(cfg.pose):
        rows = np.flatnonzero(np.asarray(cfg.pose) == pose)
        assert len(rows) == 2 and not cfg.wrench[rows[0]].any()
        w = cfg.wrench[rows[1]]
        direction = tuple(np.round(w[:3] / np.linalg.norm(w[:3])).astype(int))
        expected = sim.pull_wrench(chain, cfg.q[rows[1]], LOAD.mass, LOAD.com, direction)[0]
        np.testing.assert_allclose(w, expected, rtol=1e-6, atol=1e-6)
        used.add(direction)
    return used


def test_each_pose_picks_its_load_case_for_d_and_the_pulls_reveal_a1(kr270):
    chain = sim.Chain.from_urdf(examples.ROBOT_URDF, "tool0")
    d, down = _design(kr270, "z,x"), _design(kr270, "z")
    used = _check_pulls(d.configurations, chain)
    assert used & {(1, 0, 0), (-1, 0, 0)}  # the D criterion picks sideways pulls
    assert _check_pulls(down.configurations, chain) == {(0, 0, -1)}
    stage = d.stages["load_choice"]
    assert sum(stage["load_cases_used"].values()) == 12 and "discovery" not in d.stages
    assert any("along +x" in s or "along -x" in s for s in stage["load_cases_used"])
    # a pull puts a torque on the vertical axis A1: its compliance is designed for, and the
    # torque backlash of A1 becomes detectable; under the weight alone neither
    assert "k_a1" in d.predicted_std and "k_a1" not in down.predicted_std
    (det,) = d.detectability
    (again,) = with_detectability(d, kr270, BACKLASH, 0.05, 0.8).detectability
    assert det.detectable and det.min_detectable == pytest.approx(again.min_detectable)
    assert not down.detectability[0].detectable
    # D is the log det of the design's information, recomputed from its readings
    free = [n for n in kr270.nominal().names if n in d.predicted_std]
    params = kr270.nominal().fixed([n for n in kr270.nominal().names if n not in free], "x")
    from doe_calib.design.discovery.detection import design_readings

    _, jac = weighted_residual(kr270, design_readings(kr270, params.values, d.configurations,
                                                      SIGMA), params.values)
    j = jac[:, params.free] * params.scales[params.free]
    assert np.linalg.slogdet(j.T @ j)[1] == pytest.approx(d.value, rel=1e-8)
    assert d.value > down.value


def test_augment_with_load_directions_picks_pulls_and_reveals_a1(kr270):
    chain = sim.Chain.from_urdf(examples.ROBOT_URDF, "tool0")
    rng = np.random.default_rng(5)
    q = random_configurations(kr270.robot, 15, rng)
    cfg = load_configurations(kr270, kr270.nominal().values, q, [LOAD])  # the weight only
    measured = simulate(kr270, kr270.nominal().values, cfg, SIGMA, rng)
    r = augment_design(kr270, measured, 4, [LOAD], candidates=200, sigma=SIGMA,
                       detect=BACKLASH, rng=np.random.default_rng(1),
                       directions=parse_directions("z,x,y"))
    used = _check_pulls(r.configurations, chain)
    assert used - {(0, 0, -1)}  # sideways pulls among the new poses
    (before,), (after,) = r.detect_before, r.detect_after
    assert not before.detectable and after.detectable
    assert r.std_before["k_a2"][0] > r.std_after["k_a2"][0]
    back = json.loads(r.to_json())
    assert len(back["configurations"]) == 8


def test_load_directions_from_the_command_line_without_a_size(tmp_path, capsys):
    from doe_calib.cli import main

    out = tmp_path / "d.json"
    args = ["design", "--robot", examples.ROBOT_URDF, "--tool", examples.TOOL_YAML,
            "--model", MODEL, "--poses", "12", "--load", "250@0,0,200", "--candidates", "150",
            "--no-refine", "--no-collision", "--seed", "3", "--sigma", "0.03"]
    assert main(args + ["--detect", BACKLASH, "--load-directions", "z,x",
                        "--out", str(out)]) == 0
    saved = json.loads(out.read_text())
    assert "load_choice" in saved["stages"] and saved["detectability"][0]["effect"] == BACKLASH
    assert saved["detectability"][0]["detectable"]
    assert "D-optimal choice of poses, load cases and approach sides" in capsys.readouterr().out
    assert main(args + ["--load-directions", "z,x", "--out", str(tmp_path / "e.json")]) == 2
    assert "--detect EFFECTS alone" in capsys.readouterr().err
