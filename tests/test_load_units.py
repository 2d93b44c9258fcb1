"""A wrench written in kgf is named as such after the fit, from the robot's effort limits.

Campaigns from ``independent_sim``: realistic joint compliances (a few tenths of a degree
at the URDF's effort limit) under a payload, written once in N and once with the wrench
columns divided by g_n = 9.80665 (kgf).
"""
import csv

import independent_sim as sim
from markered_robot import markered_robot
import numpy as np
import pytest

from doe_calib import build_model, examples
from doe_calib.cli import main
from doe_calib.diagnosis import diagnose
from doe_calib.estimation.identify import identify_quietly
from doe_calib.io.csv_files import read_measurements

MARKERS = {"A": [0.15, 0.0, 0.08], "B": [-0.075, 0.13, 0.08], "C": [-0.075, -0.13, 0.08]}
MODEL = "joint_offset+geometry+joint_compliance"
KGF = 9.80665


def _in_kgf(src, dst):
    with open(src, newline="") as fh:
        rows = list(csv.reader(fh))
    at = [rows[0].index(c) for c in sim.WRENCH]
    for r in rows[1:]:
        for i in at:
            r[i] = repr(float(r[i]) / KGF)
    with open(dst, "w", newline="") as fh:
        csv.writer(fh).writerows(rows)


def _campaign(tmp_path, urdf, mass, compliance, seed):
    """N and kgf files of one campaign; ``compliance`` {joint index: rad/(N·m)}."""
    chain, robot, tool = markered_robot(urdf, "tool0", MARKERS)
    rng = np.random.default_rng(seed)
    effects = tuple(sim.SmoothAngleCompliance(k, c, 0.0) for k, c in compliance.items())
    truth = sim.Truth.random(chain, np.array(list(MARKERS.values())), rng, effects=effects)
    q = sim.random_configurations(chain, 30, rng)
    q, w = sim.unloaded_and_loaded(chain, q, mass, [0.0, 0.0, 0.1])
    newton, kgf = tmp_path / "n.csv", tmp_path / "kgf.csv"
    sim.write_campaign(newton, chain, truth, q, w, list(MARKERS), 0.03, rng)
    _in_kgf(newton, kgf)
    return robot, tool, newton, kgf


def _ur10():
    path = sim.ur10_urdf()
    if path is None:
        pytest.skip("example-robot-data (UR10 URDF) is not installed")
    return path


@pytest.mark.parametrize("arm", ["kr270", "ur10"])
def test_a_wrench_in_kgf_is_named_with_the_factor(tmp_path, arm):
    # the KR 270 under 250 kg, the UR10 under 10 kg; compliances 0.2–0.43° at the effort limit
    urdf, mass, compliance = {"kr270": (examples.ROBOT_URDF, 250.0, {1: 3e-7, 2: 5e-7}),
                              "ur10": (_ur10(), 10.0, {1: 1e-5, 2: 4e-5})}[arm]
    robot, tool, newton, kgf = _campaign(tmp_path, urdf, mass, compliance, seed=31)
    model = build_model(robot, tool, MODEL)
    good = identify_quietly(model, read_measurements(newton, robot, tool))
    assert not any("kgf" in w for w in good.warnings), good.warnings
    bad = identify_quietly(model, read_measurements(kgf, robot, tool))
    found = [w for w in bad.warnings if "look like kgf" in w]
    assert len(found) == 1, bad.warnings
    # the compliances come out g_n times the truth, and the message says by how much it twists
    for k, c in compliance.items():
        j = robot.joints[k]
        fitted = bad[f"k_{j.name}"]
        assert fitted.value == pytest.approx(KGF * c, abs=4 * fitted.std + 0.03 * KGF * c)
    worst = max(compliance, key=lambda k: compliance[k] * robot.joints[k].effort)
    j = robot.joints[worst]
    stated = float(found[0].split(f"joint {j.name} twists it by ")[1].split("°")[0])
    assert stated == pytest.approx(np.degrees(KGF * compliance[worst] * j.effort), rel=0.1)
    # pinocchio's gravity is 9.81: the force of the mass, read as kgf
    assert f"of {mass * 9.81 / KGF:.4g} kg in kgf" in found[0]
    assert f"Multiply the six wrench columns by {KGF}" in found[0]


def test_the_cli_warns_of_kgf_and_not_of_newtons(tmp_path, capsys):
    robot, tool, newton, kgf = _campaign(tmp_path, examples.ROBOT_URDF, 250.0,
                                         {1: 3e-7, 2: 5e-7}, seed=32)
    tool_file = tmp_path / "tool.yaml"
    tool_file.write_text("flange: tool0\nmarkers:\n" + "".join(
        f"  {k}: [{v[0] * 1e3:g}, {v[1] * 1e3:g}, {v[2] * 1e3:g}]\n" for k, v in MARKERS.items()))
    for data, named in ((newton, False), (kgf, True)):
        code = main(["identify", "--robot", str(examples.ROBOT_URDF), "--tool", str(tool_file),
                     "--data", str(data), "--model", MODEL, "--out", str(tmp_path / "r.json")])
        text = " ".join(capsys.readouterr().err.split())
        assert code == 0 and ("the wrench columns (fx, fy, fz, mx, my, mz) look like kgf"
                              in text) == named, text


def test_diagnose_notes_a_wrench_in_kgf(tmp_path):
    robot, tool, newton, kgf = _campaign(tmp_path, examples.ROBOT_URDF, 250.0,
                                         {1: 3e-7, 2: 5e-7}, seed=33)
    model = build_model(robot, tool, MODEL)
    for data, named in ((newton, False), (kgf, True)):
        d = diagnose(model, read_measurements(data, robot, tool))
        assert any("look like kgf" in n for n in d.notes) == named, d.summary()
