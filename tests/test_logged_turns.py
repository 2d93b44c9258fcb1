"""A ±360° arm's program logs a pose's loaded pass a turn away from its unloaded pass: the file
identifies as the unturned one does (io/logged_turns.py). Campaigns from ``independent_sim``
on a UR5 (every joint ±360°), two load passes."""
import csv
from importlib import metadata

import independent_sim as sim
import numpy as np
import pytest
from markered_robot import markered_robot

from doe_calib import build_model
from doe_calib.cli import main
from doe_calib.errors import DataError
from doe_calib.estimation.identify import identify_quietly
from doe_calib.io.csv_files import read_measurements

MARKERS = {"A": [0.1, 0.0, 0.06], "B": [-0.05, 0.0866, 0.06], "C": [-0.05, -0.0866, 0.06]}
MODEL = "joint_offset+geometry+joint_compliance"
TURNED = (0, 3, 5)  # q1, q4, q6 logged a turn away in the loaded pass


def _ur5():
    try:
        files = metadata.distribution("example-robot-data").files or []
    except metadata.PackageNotFoundError:
        pytest.skip("the UR5 URDF needs `pip install example-robot-data`")
    found = [f for f in files if str(f).endswith("ur_description/urdf/ur5_robot.urdf")]
    if not found:
        pytest.skip("ur5_robot.urdf is not in example-robot-data")
    return found[0].locate()


def _turned(src, dst, shift):
    """``src`` with the q of every loaded row moved by ``shift(q)`` deg on :data:`TURNED`."""
    with open(src, newline="") as fh:
        rows = list(csv.reader(fh))
    force = rows[0].index("fz")
    for r in rows[1:]:
        if float(r[force]) != 0.0:
            for k in TURNED:
                r[1 + k] = repr(float(r[1 + k]) + shift(float(r[1 + k])))
    with open(dst, "w", newline="") as fh:
        csv.writer(fh).writerows(rows)


@pytest.fixture(scope="module")
def campaign(tmp_path_factory):
    tmp = tmp_path_factory.mktemp("turns")
    chain, robot, tool = markered_robot(_ur5(), "tool0", MARKERS)
    rng = np.random.default_rng(7)
    truth = sim.Truth.random(chain, np.array(list(MARKERS.values())), rng,
                             effects=(sim.SmoothAngleCompliance(1, 2e-5, 0.0),))
    q = sim.random_configurations(chain, 30, rng, margin=0.3)  # |q| ≤ 0.4 of 720°
    q, w = sim.unloaded_and_loaded(chain, q, 5.0, [0.0, 0.0, 0.1])
    plain = tmp / "plain.csv"
    sim.write_campaign(plain, chain, truth, q, w, list(MARKERS), 0.02, rng)
    return robot, tool, plain


def test_a_pass_logged_a_turn_away_identifies_as_the_unturned_one(campaign, tmp_path, capsys):
    robot, tool, plain = campaign
    logged = tmp_path / "logged.csv"
    _turned(plain, logged, lambda v: -360.0 if v > 0 else 360.0)  # the nearer equivalent
    before, after = (read_measurements(p, robot, tool) for p in (plain, logged))
    assert not before.warnings
    note = [w for w in after.warnings if "a whole turn apart" in w]
    assert len(note) == 1 and note[0].startswith("30 pose(s) logged a whole turn apart (q1, "
                                                 "q4, q6)"), after.warnings
    assert "kept as one pose, every row at its own logged q" in note[0]
    # one pose, two configurations as before; each row at its logged q
    assert after.configurations.pose == before.configurations.pose
    loaded = np.any(after.configurations.wrench != 0, axis=1)
    step = np.degrees(after.configurations.q - before.configurations.q)
    assert np.allclose(np.abs(step[loaded][:, TURNED]), 360.0) and not step[~loaded].any()
    model = build_model(robot, tool, MODEL)
    a, b = (identify_quietly(model, m) for m in (before, after))
    assert np.allclose(a.parameters.values, b.parameters.values, rtol=1e-7, atol=1e-12)
    assert a.sigma_mm == pytest.approx(b.sigma_mm, rel=1e-9)
    tool_yaml = tmp_path / "tool.yaml"  # the command says so
    tool_yaml.write_text("flange: tool0\nmarkers:\n" + "".join(
        f"  {k}: [{', '.join(f'{1000 * c:g}' for c in v)}]\n" for k, v in MARKERS.items()))
    assert main(["identify", "--robot", str(_ur5()), "--flange", "tool0", "--tool",
                 str(tool_yaml), "--model", MODEL, "--data", str(logged), "--select", "none",
                 "--out", str(tmp_path / "r.json")]) == 0
    assert "warning: 30 pose(s) logged a whole turn apart" in capsys.readouterr().err


def test_rows_a_turn_and_a_bit_apart_are_still_refused(campaign, tmp_path):
    robot, tool, plain = campaign
    bad = tmp_path / "bad.csv"
    _turned(plain, bad, lambda v: -359.5 if v > 0 else 359.5)
    with pytest.raises(DataError) as err:
        read_measurements(bad, robot, tool)
    assert err.value.line == 5 and err.value.column == "'q1' (2)"  # the first loaded row
    assert "all rows of a pose share q" in str(err.value)
