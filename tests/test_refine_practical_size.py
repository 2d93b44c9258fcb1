"""``refine --practical-um`` (diagnosis/refine.py → diagnose): on a correct model
fitted to many readings whose σ is stated 15 % too small (independently simulated), the
misfit beyond the noise, σ·√(1.15² − 1) ≈ 2.5 µm, makes the final verdict "not adequate"
at the default practical size of 2 µm and "adequate" at 4 µm; no effect is added either way."""
import json

import independent_sim as sim
from markered_robot import markered_robot
import numpy as np
import pytest

from doe_calib import build_model, examples
from doe_calib.diagnosis.refine import refine
from doe_calib.diagnosis.settings import RefineSettings
from doe_calib.io.csv_files import read_measurements

MARKERS = {"A": [0.15, 0.0, 0.08], "B": [-0.075, 0.13, 0.08], "C": [-0.075, -0.13, 0.08],
           "D": [0.0, 0.15, 0.12], "E": [0.1, -0.1, 0.04], "F": [-0.12, 0.0, 0.16]}
NOISE_MM = 0.005
STATED_MM = NOISE_MM / 1.15  # σ given 15 % too small: beyond the 5 % tolerance
START = "joint_offset+geometry"


@pytest.fixture(scope="module")
def campaign(tmp_path_factory):
    tmp = tmp_path_factory.mktemp("refine_practical")
    chain, robot, tool = markered_robot(examples.ROBOT_URDF, "tool0", MARKERS)
    rng = np.random.default_rng(81)
    truth = sim.Truth.random(chain, np.array(list(MARKERS.values())), rng)
    q = sim.random_configurations(chain, 300, rng)  # 5 400 coordinates
    sim.write_campaign(tmp / "m.csv", chain, truth, q, np.zeros((len(q), 6)), list(MARKERS),
                       NOISE_MM, rng, write_sigma=False)  # σ from --sigma / sigma_mm
    tool_yaml = tmp / "tool.yaml"
    tool_yaml.write_text("flange: tool0\nmarkers:\n" + "".join(
        f"  {k}: [{', '.join(f'{1000 * c:g}' for c in v)}]\n" for k, v in MARKERS.items()))
    return tmp, robot, tool, tool_yaml


def test_refine_default_practical_size_leaves_the_misfit_not_adequate(campaign):
    tmp, robot, tool, _ = campaign
    meas = read_measurements(tmp / "m.csv", robot, tool)
    out = refine(build_model(robot, tool, START), meas, sigma=STATED_MM / 1000,
                 settings=RefineSettings(max_steps=2))
    c = out.diagnosis.chi2
    expected = 1e3 * STATED_MM * np.sqrt(1.15 ** 2 - 1)  # 2.47 µm
    assert c["misfit_um"] == pytest.approx(expected, abs=0.4), c
    assert c["practical_um"] == 2.0 and c["sigma_ratio"] > 1.05
    assert len(out.steps) == 1 and out.fit.model == START  # no effect is added …
    assert not out.diagnosis.adequate and "not adequate" in out.stopped  # … nor excused


def test_refine_practical_um_from_the_command_line_calls_it_adequate(campaign, capsys):
    from doe_calib.cli import main

    tmp, _, _, tool_yaml = campaign
    out = tmp / "r.json"
    assert main(["refine", "--robot", examples.ROBOT_URDF, "--flange", "tool0", "--tool",
                 str(tool_yaml), "--data", str(tmp / "m.csv"), "--model", START,
                 "--sigma", f"{STATED_MM:.9f}", "--max-steps", "2", "--practical-um", "4",
                 "--out", str(out)]) == 0
    history = json.loads((tmp / "r_refine.json").read_text())
    chi2 = history["diagnosis"]["chi2"]
    assert chi2["practical_um"] == 4.0 and 2.0 < chi2["misfit_um"] < 4.0, chi2
    assert history["diagnosis"]["adequate"] and len(history["steps"]) == 1
    assert "below the practical size of 4 µm" in history["diagnosis"]["verdict"]
    assert "the model is adequate" in capsys.readouterr().out


def test_refine_tolerance_from_the_command_line(campaign):
    """``--tolerance 0.2`` reaches refine's diagnoses: σ̂/σ ≈ 1.15 is then within the noise."""
    from doe_calib.cli import main

    tmp, _, _, tool_yaml = campaign
    out = tmp / "t.json"
    assert main(["refine", "--robot", examples.ROBOT_URDF, "--flange", "tool0", "--tool",
                 str(tool_yaml), "--data", str(tmp / "m.csv"), "--model", START,
                 "--sigma", f"{STATED_MM:.9f}", "--max-steps", "2", "--tolerance", "0.2",
                 "--out", str(out)]) == 0
    history = json.loads((tmp / "t_refine.json").read_text())
    assert 1.05 < history["diagnosis"]["chi2"]["sigma_ratio"] < 1.2
    assert history["diagnosis"]["adequate"] and len(history["steps"]) == 1
    assert "within 20% of the noise" in history["diagnosis"]["verdict"]
