"""A single gross outlier is named as one before any effect; a genuine effect is not an outlier.

Campaigns from ``independent_sim`` (Pinocchio, not doe_calib's model) on the KR 270 example
with a three-marker plate, σ 0.03 mm, each pose unloaded and under 250 kg.
"""
import json

import independent_sim as sim
from markered_robot import markered_robot
import numpy as np
import pytest

from doe_calib import build_model, examples
from doe_calib.cli import main
from doe_calib.diagnosis import diagnose
from doe_calib.diagnosis.refine import refine
from doe_calib.diagnosis.outliers import gross_outliers, within_pose
from doe_calib.diagnosis.result import DiagnosisResult
from doe_calib.diagnosis.settings import RefineSettings
from doe_calib.estimation.identify import identify_quietly
from doe_calib.estimation.sigma import resolve_sigma
from doe_calib.io.csv_files import read_measurements

MARKERS = {"A": [0.15, 0.0, 0.08], "B": [-0.075, 0.13, 0.08], "C": [-0.075, -0.13, 0.08]}
START = "joint_offset+geometry+joint_compliance"
SIGMA_MM = 0.03
ROW, SHIFT = 100, np.array([0.9, -1.2, 0.0])  # 1.5 mm on data row 100 (pose 17, marker B)


@pytest.fixture(scope="module")
def kr270():
    return markered_robot(examples.ROBOT_URDF, "tool0", MARKERS)


def _campaign(path, kr270, seed, outliers=(), effects=(), write_sigma=True):
    chain, robot, tool = kr270
    rng = np.random.default_rng(seed)
    truth = sim.Truth.random(chain, np.array(list(MARKERS.values())), rng, effects=effects)
    q = sim.random_configurations(chain, 40, rng)
    q, w = sim.unloaded_and_loaded(chain, q, 250.0, [0.0, 0.0, 0.1])
    info = sim.write_campaign(path, chain, truth, q, w, list(MARKERS), SIGMA_MM, rng,
                              outliers=outliers, write_sigma=write_sigma)
    return read_measurements(path, robot, tool), info


def _where(meas, info, row):
    """Pose, marker and file line of data row ``row`` as the simulator wrote it."""
    line = row + 2  # line 1 is the header
    config, marker = info["rows"][row]
    i = int(np.flatnonzero(meas.line == line)[0])
    assert meas.marker[i] == marker
    return meas.configurations.pose[meas.config[i]], list(MARKERS)[marker], line


def test_one_gross_reading_is_named_before_any_effect(kr270, tmp_path):
    _, robot, tool = kr270
    meas, info = _campaign(tmp_path / "m.csv", kr270, 25, outliers=((ROW, SHIFT),))
    pose, marker, line = _where(meas, info, ROW)
    d = diagnose(build_model(robot, tool, START), meas)
    assert d.proposed is None and not d.adequate and d.candidates == ()
    (o,) = d.outliers
    assert (o.pose, o.marker, o.line) == (pose, marker, line)
    # the deletion residual is the displacement plus the noise of one reading (σ √3 in norm)
    assert o.size_mm == pytest.approx(np.linalg.norm(SHIFT), abs=5 * SIGMA_MM * np.sqrt(3))
    assert o.size_sigma == pytest.approx(o.size_mm / SIGMA_MM, rel=1e-9)
    assert d.gross_errors == (pose,)
    assert "one reading is a gross error, not an effect" in d.verdict
    assert f"--exclude-poses {pose}" in d.verdict and f"line {line} of" in d.verdict
    back = DiagnosisResult.from_dict(json.loads(d.to_json()))
    assert back.outliers == d.outliers
    # refine stops at the starting model, naming the outlier instead of an effect
    out = refine(build_model(robot, tool, START), meas, settings=RefineSettings(max_steps=2))
    assert len(out.steps) == 1 and out.stopped.startswith("no effect tested")
    assert f"pose {pose}, marker {marker}" in out.stopped
    # what the verdict advises works: without the pose the model fits the noise
    kept, _ = meas.split_by_pose([pose])
    rest = diagnose(build_model(robot, tool, START), kept)
    assert rest.adequate and not rest.outliers and rest.proposed is None, rest.summary()


def test_a_gross_reading_is_found_with_sigma_estimated_too(kr270, tmp_path):
    _, robot, tool = kr270
    meas, info = _campaign(tmp_path / "m.csv", kr270, 26, outliers=((ROW, SHIFT),),
                           write_sigma=False)
    model = build_model(robot, tool, START)
    settled = resolve_sigma(model, meas).measurements  # σ̂ of the fit, inflated by the outlier
    assert settled.sigma[0] * 1e3 > 1.5 * SIGMA_MM
    (o,) = gross_outliers(model, settled, identify_quietly(model, settled))
    assert (o.pose, o.marker, o.line) == _where(meas, info, ROW)
    # judged on the σ̂ of the other readings: the true σ within 10 %
    assert o.size_mm / o.size_sigma == pytest.approx(SIGMA_MM, rel=0.1)


@pytest.mark.parametrize("write_sigma", [True, False])
def test_a_hidden_effect_is_not_an_outlier(kr270, tmp_path, write_sigma):
    # a gravity compensator on a2: its compliance changes with the angle (as in the README demo)
    _, robot, tool = kr270
    hidden = sim.SmoothAngleCompliance(1, 0.0, 6e-7, phase=0.3)
    meas, _ = _campaign(tmp_path / "m.csv", kr270, 27, effects=(hidden,),
                        write_sigma=write_sigma)
    model = build_model(robot, tool, START)
    meas = resolve_sigma(model, meas).measurements
    fit = identify_quietly(model, meas)
    misfit = fit.sigma_ratio * np.median(meas.sigma) * 1e3 / SIGMA_MM  # σ̂ / true σ
    assert misfit > 3  # the effect is far beyond the noise, in many poses
    assert gross_outliers(model, meas, fit) == ()
    if write_sigma:
        d = diagnose(model, meas, fit)
        assert d.proposed and d.proposed.startswith("compliance_by_angle(j2"), d.summary()
        assert not d.outliers


def test_the_cli_names_the_outlier(kr270, tmp_path, capsys):
    meas, info = _campaign(tmp_path / "m.csv", kr270, 25, outliers=((ROW, SHIFT),))
    pose, marker, line = _where(meas, info, ROW)
    tool = tmp_path / "tool.yaml"
    tool.write_text("flange: tool0\nmarkers:\n" + "".join(
        f"  {k}: [{v[0] * 1e3:g}, {v[1] * 1e3:g}, {v[2] * 1e3:g}]\n" for k, v in MARKERS.items()))
    out = tmp_path / "d.json"
    code = main(["diagnose", "--robot", str(examples.ROBOT_URDF), "--tool", str(tool), "--data",
                 str(tmp_path / "m.csv"), "--model", START, "--out", str(out)])
    text = " ".join(capsys.readouterr().out.split())
    assert code == 0 and f"pose {pose}, marker {marker} (line {line} of" in text, text
    assert json.loads(out.read_text())["outliers"][0]["line"] == line


def test_within_pose_noise_ignores_any_rigid_motion_of_a_pose():
    # 400 poses of 1-4 markers: each moved rigidly by ~5 (as an effect moves the flange), plus
    # unit noise; what a rigid motion cannot make has 0, 1, 3, 6 dof and mean square 1
    rng = np.random.default_rng(0)
    pred, err, cfg = [], [], []
    for c in range(400):
        n = c % 4 + 1
        x = rng.normal(size=(n, 3)) * 0.1 + rng.normal(size=3)
        t, w = rng.normal(size=(2, 3)) * 5
        pred.append(x)
        err.append(t + np.cross(w, x - x.mean(axis=0)) + rng.normal(size=(n, 3)))
        cfg += [c] * n
    pred, err, cfg = np.vstack(pred), np.vstack(err), np.array(cfg)
    ss, dof = within_pose(err, pred, cfg, np.ones(len(cfg), bool))
    assert dof == 100 * (0 + 1 + 3 + 6)
    assert ss / dof == pytest.approx(1.0, abs=4 * np.sqrt(2 / dof))
    keep = cfg != 3  # a pose with a reading left out does not count
    assert within_pose(err, pred, cfg, keep)[1] == dof - 6
