"""A backlash by approach whose file writes the approach directions reversed: the verdict leads
with it, says what its negative width means and why, and ``--approach-sign reversed`` makes
refine add it with a positive width (independently simulated readings)."""
import json

import independent_sim as sim
import numpy as np
import pytest

from doe_calib import Robot, Tool, build_model, examples
from doe_calib.cli import main
from doe_calib.diagnosis import diagnose
from doe_calib.io.csv_files import read_measurements

MARKERS = {"A": [0.15, 0.0, 0.08], "B": [-0.075, 0.13, 0.08], "C": [-0.075, -0.13, 0.08]}
WIDTH_DEG = 0.02
START = "joint_offset+geometry"


@pytest.fixture(scope="module")
def reversed_file(tmp_path_factory):
    """Unloaded poses, each joint reached from a random side; a hidden 0.02° approach backlash
    on joint 2; the approach columns written with the opposite sign."""
    chain = sim.Chain.from_urdf(examples.ROBOT_URDF, "tool0")
    rng = np.random.default_rng(61)
    truth = sim.Truth.random(chain, np.array(list(MARKERS.values())), rng,
                             effects=(sim.ApproachBacklash(1, np.radians(WIDTH_DEG)),))
    q = sim.random_configurations(chain, 80, rng)
    approach = rng.choice([-1.0, 1.0], size=q.shape)
    path = tmp_path_factory.mktemp("approach") / "m.csv"
    sim.write_campaign(path, chain, truth, q, np.zeros((len(q), 6)), list(MARKERS), 0.02, rng,
                       approach=approach, written_approach_sign=-1.0)
    return path


def _kr270():
    robot = Robot.from_urdf(examples.ROBOT_URDF, flange="tool0")
    tool = Tool.from_markers({k: np.multiply(v, 1e3) for k, v in MARKERS.items()},
                             flange="tool0")
    return robot, tool


def test_a_reversed_approach_backlash_leads_the_verdict(reversed_file):
    robot, tool = _kr270()
    model = build_model(robot, tool, START)
    d = diagnose(model, read_measurements(reversed_file, robot, tool))
    odd = next(c for c in d.candidates if c.spec.startswith("backlash(j2"))
    width = next(s for s in odd.sizes if s.name == "backlash_a2")
    # the fit finds the band, with the sign reversed: −0.02° within 3σ
    assert width.value == pytest.approx(-WIDTH_DEG, abs=3 * width.std + 1e-4), odd
    assert odd.cv_gain > 0.5 and not odd.proposed and odd.implausible
    others = [c.cv_gain for c in d.candidates if c.cv_gain is not None
              and not c.spec.startswith("backlash(j2")]
    assert odd.cv_gain > 2 * max(others)
    v = d.verdict
    assert v.startswith("Backlash of joint 2"), v  # leads, before any weaker effect
    assert "impossible sign" in v and "negative usually means the approach directions" in v
    assert "not in measurement order" in v and "link-side" in v
    assert "--approach-sign reversed" in v
    assert "Not proposed although it predicts better" not in v


def test_refine_with_the_approach_sign_reversed_adds_a_positive_band(reversed_file, tmp_path,
                                                                       capsys):
    argv = ["refine", "--robot", examples.ROBOT_URDF, "--tool", tmp_path / "tool.yaml",
            "--data", reversed_file, "--model", START, "--max-steps", "1",
            "--approach-sign", "reversed", "--out", tmp_path / "r.json"]
    (tmp_path / "tool.yaml").write_text(
        "flange: tool0\nmarkers:\n" + "".join(f"  {k}: [{', '.join(str(1e3 * x) for x in v)}]\n"
                                               for k, v in MARKERS.items()), encoding="utf-8")
    assert main([str(a) for a in argv]) == 0
    assert "approach directions reversed at your request" in capsys.readouterr().err
    history = json.loads((tmp_path / "r_refine.json").read_text())
    added = history["steps"][1]["added"]
    assert added.startswith("backlash(j2"), history["steps"]
    result = json.loads((tmp_path / "r.json").read_text())
    row = next(p for p in result["parameters"] if p["name"] == "backlash_a2")
    assert row["value"] == pytest.approx(WIDTH_DEG, abs=3 * row["std"] + 1e-4), row


def test_reversing_twice_gives_the_readings_back(reversed_file):
    robot, tool = _kr270()
    meas = read_measurements(reversed_file, robot, tool)
    once = meas.with_approach_reversed()
    assert np.array_equal(once.configurations.approach, -meas.configurations.approach)
    assert np.abs(meas.configurations.approach).sum() > 0
    again = once.with_approach_reversed().configurations
    assert np.array_equal(again.env, meas.configurations.env, equal_nan=True)
