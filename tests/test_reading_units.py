"""Readings written in metres are named as such, from the robot's own geometry (reading_units)."""
import csv
from dataclasses import replace

import independent_sim as sim
from markered_robot import markered_robot
import numpy as np
import pytest

from doe_calib import build_model, examples
from doe_calib.cli import main
from doe_calib.errors import DataError
from doe_calib.estimation.identify import identify_quietly
from doe_calib.io.csv_files import read_measurements
from doe_calib.io.probe_file import read_probe

MARKERS = {"A": [0.15, 0.0, 0.08], "B": [-0.075, 0.13, 0.08], "C": [-0.075, -0.13, 0.08]}


@pytest.fixture(scope="module")
def kr270():
    return markered_robot(examples.ROBOT_URDF, "tool0", MARKERS)


def _in_metres(src, dst):
    """``src`` with its x, y, z divided by 1000; returns those values (K, 3) as written."""
    with open(src, newline="") as fh:
        rows = list(csv.reader(fh))
    at = [rows[0].index(c) for c in "xyz"]
    for r in rows[1:]:
        for i in at:
            r[i] = repr(float(r[i]) / 1000.0)
    with open(dst, "w", newline="") as fh:
        csv.writer(fh).writerows(rows)
    return np.array([[float(r[i]) for i in at] for r in rows[1:]])


def _rms_spread(xyz):
    return float(np.sqrt(np.mean(np.sum((xyz - xyz.mean(axis=0)) ** 2, axis=1))))


def _campaign(tmp_path, kr270, seed=1):
    chain, robot, tool = kr270
    rng = np.random.default_rng(seed)
    truth = sim.Truth.random(chain, np.array(list(MARKERS.values())), rng)
    q = sim.random_configurations(chain, 15, rng)
    path = tmp_path / "mm.csv"
    info = sim.write_campaign(path, chain, truth, q, np.zeros((len(q), 6)), list(MARKERS), 0.03,
                              rng)
    return path, info


def test_readings_in_metres_are_refused_naming_the_file_and_the_spread(kr270, tmp_path):
    _, robot, tool = kr270
    good, info = _campaign(tmp_path, kr270)
    meas = read_measurements(good, robot, tool)
    assert not meas.warnings
    bad = tmp_path / "m.csv"
    written = _in_metres(good, bad)
    with pytest.raises(DataError) as caught:
        read_measurements(bad, robot, tool)
    text = str(caught.value)
    assert text.startswith(f"{bad}: x, y, z look like metres, not mm")
    assert f"the readings spread {_rms_spread(written):.3g} about their centre" in text
    # the true marker positions (m) spread as far as the nominal robot puts them, within mm
    true_spread_mm = _rms_spread(info["exact"].reshape(-1, 3)) * 1e3
    shown = float(text.split("puts these points ")[1].split(" mm")[0])
    assert shown == pytest.approx(true_spread_mm, abs=5.0)
    assert "1000× more" in text and "multiply x, y, z by 1000" in text
    reach = sum(np.linalg.norm(j.placement_matrix[:3, 3]) for j in robot.joints) + \
        np.linalg.norm(np.array(robot.flange_placement).reshape(4, 4)[:3, 3])
    assert f"reaches about {reach:.2f} m" in text


def test_metres_stop_the_cli_before_any_fit(kr270, tmp_path, capsys):
    _, robot, tool = kr270
    good, _ = _campaign(tmp_path, kr270, seed=2)
    bad = tmp_path / "m.csv"
    _in_metres(good, bad)
    tool_file = tmp_path / "tool.yaml"
    tool_file.write_text("flange: tool0\nmarkers:\n" + "".join(
        f"  {k}: [{v[0] * 1e3:g}, {v[1] * 1e3:g}, {v[2] * 1e3:g}]\n" for k, v in MARKERS.items()))
    out = tmp_path / "r.json"
    for command in ("identify", "diagnose"):
        code = main([command, "--robot", str(examples.ROBOT_URDF), "--tool", str(tool_file),
                     "--data", str(bad), "--model", "joint_offset", "--out", str(out)])
        err = capsys.readouterr().err.strip().splitlines()[-1]
        assert code == 2 and err.startswith(f"error: {bad}: x, y, z look like metres"), err
        assert not out.exists()


def test_metres_in_readings_built_in_code_are_named_after_the_fit(kr270, tmp_path):
    _, robot, tool = kr270
    good, _ = _campaign(tmp_path, kr270, seed=3)
    meas = read_measurements(good, robot, tool)
    model = build_model(robot, tool, "joint_offset")
    assert not any("metres" in w for w in identify_quietly(model, meas).warnings)
    res = identify_quietly(model, replace(meas, xyz=meas.xyz / 1000.0))
    assert sum("x, y, z look like metres" in w for w in res.warnings) == 1, res.warnings


def test_a_probe_file_in_metres_is_refused(kr270, tmp_path):
    chain, robot, _ = kr270
    rng = np.random.default_rng(4)
    truth = sim.Truth.random(chain, np.zeros((1, 3)), rng)
    q = sim.random_configurations(chain, 12, rng)
    good = tmp_path / "probe.csv"
    sim.write_probe_campaign(good, chain, truth, q, np.zeros((len(q), 6)), np.eye(3),
                             [0.0, 0.0, 0.15], "xyz", 0.02, 0.005, rng)
    assert len(read_probe(good, robot, "rpy")) == 12
    bad = tmp_path / "probe_m.csv"
    _in_metres(good, bad)
    with pytest.raises(DataError, match="probe_m.csv: x, y, z look like metres, not mm"):
        read_probe(bad, robot, "rpy")
