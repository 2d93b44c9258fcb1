"""``diagnose`` and ``refine`` on plane touches and ballbar lengths (issue #31), judged on
campaigns simulated independently of our model, with and without an effect the geometric
model lacks.

The truth of tests/test_socket_diagnosis.py (a UR10 with placement errors up to 0.5 mm /
0.05°, joint offsets up to 0.1°, the ball centre 1 mm off nominal), with or without a
twice-per-revolution transmission error of 0.03° in the shoulder (joint 2). Plane touches:
a table top and two faces of a block, touched by IK on the truth (scatter 0.01 mm along the
normal). Ballbar: arcs about two pivots on the table at 150, 225 and 300 mm, lengths read
to 0.001 mm. Touches see neither the base pose nor the scale (new configurations compared
after a similarity registration), lengths see the scale (a rigid registration).
"""
import csv
import json

import independent_sim as sim
import numpy as np
import pytest
from seated_contacts import q_columns, write_lengths, write_touches

from doe_calib.cli import main

SHOULDER = sim.Cyclic(1, np.radians(0.03), 2)  # joint 2, 2 per revolution
MODEL = "joint_offset+geometry"
TOUCH_MM, BAR_MM = 0.01, 0.001
PLANES = {"table": ([0.3, 0.0, 0.05], [1, 0, 0], [0, 1, 0], 0.45),
          "front": ([0.75, 0.0, 0.35], [0, 1, 0], [0, 0, 1], 0.2),
          "slant": ([0.1, -0.7, 0.35], [1, 0, 0], [0, 1 / np.sqrt(2), 1 / np.sqrt(2)], 0.2)}
PER_PLANE = 30
PIVOTS_M = {"P1": [0.55, 0.30, 0.05], "P2": [0.20, -0.65, 0.05]}
LENGTHS_MM = (150.0, 225.0, 300.0)


def _truth(ur10, effects):
    return sim.ball_on_stem_truth(ur10, effects)


def _campaigns(ur10, d, effects):
    """Touches, lengths and new configurations of the truth with ``effects``, written in
    ``d``: (d, truth, new configurations (40, 6) rad)."""
    truth = _truth(ur10, effects)
    write_touches(d / "touches.csv", ur10, truth, np.random.default_rng(17), PLANES, PER_PLANE,
                  TOUCH_MM)
    write_lengths(d / "ballbar.csv", ur10, truth, np.random.default_rng(18), PIVOTS_M,
                  LENGTHS_MM, noise_mm=BAR_MM)
    (d / "tool.yaml").write_text("flange: tool0\nmarkers:\n  ball: [0.0, 0.0, 100.0]\n")
    q_new = sim.random_configurations(ur10, 40, np.random.default_rng(99),
                                      within=np.c_[-np.pi * np.ones(6), np.pi * np.ones(6)])
    with open(d / "new.csv", "w", newline="") as f:
        writer = csv.DictWriter(f, fieldnames=["pose", *q_columns(q_new[0]), "marker"])
        writer.writeheader()
        writer.writerows({"pose": str(i), **q_columns(q), "marker": "ball"}
                         for i, q in enumerate(q_new))
    return d, truth, q_new


@pytest.fixture(scope="module")
def geometric(ur10, tmp_path_factory):
    return _campaigns(ur10, tmp_path_factory.mktemp("geometric"), ())


@pytest.fixture(scope="module")
def shoulder(ur10, tmp_path_factory):
    return _campaigns(ur10, tmp_path_factory.mktemp("shoulder"), (SHOULDER,))


def _args(d, command, data, out, *more):
    sigma = TOUCH_MM if data == "touches" else BAR_MM
    return [command, "--robot", str(sim.ur10_urdf()), "--tool", str(d / "tool.yaml"),
            "--data", str(d / f"{data}.csv"), "--sigma", str(sigma), "--model", MODEL,
            "--out", str(out), *more]


def _registered_rms_mm(predicted, true, scale):
    """3-D RMS (mm) after the best rigid motion (Kabsch) of ``predicted`` onto ``true``; with
    ``scale``, the best similarity (Umeyama)."""
    a, b = predicted - predicted.mean(0), true - true.mean(0)
    u, s, vt = np.linalg.svd(a.T @ b)
    d = np.diag([1.0, 1.0, np.sign(np.linalg.det(u @ vt))])
    rot = (u @ d @ vt).T
    grow = np.trace(np.diag(s) @ d) / np.sum(a * a) if scale else 1.0
    return float(np.sqrt(np.mean(np.sum((grow * a @ rot.T - b) ** 2, axis=1))) * 1e3)


def _held_out_mm(d, result, ur10, truth, q_new, scale):
    out = d / f"{result.stem}-pred.csv"
    assert main(["predict", "--result", str(result), "--data", str(d / "new.csv"),
                 "--out", str(out)]) == 0
    with open(out) as f:
        pred = np.array([[float(r[c]) for c in "xyz"] for r in
                         csv.DictReader(line for line in f if not line.startswith("#"))]) / 1e3
    true = sim.marker_positions(ur10, truth, q_new, np.zeros((len(q_new), 6)))[:, 0]
    return _registered_rms_mm(pred, true, scale)


@pytest.mark.parametrize("truth", ["geometric", "shoulder"])
@pytest.mark.parametrize("data", ["touches", "ballbar"])
def test_diagnose_proposes_only_what_the_truth_has(request, truth, data):
    """A touch or a length is one coordinate and each plane or pivot costs 3: the χ² and F
    tests count them so, and a geometric truth gets no proposal; the shoulder's cyclic error
    is named."""
    d, _, _ = request.getfixturevalue(truth)
    missing = truth == "shoulder"
    out_file = d / f"{data}-diag.json"
    assert main(_args(d, "diagnose", data, out_file)) == 0
    out = json.loads(out_file.read_text())
    print(data, "missing" if missing else "geometric", out["proposed"], out["verdict"][:300])
    top = out["candidates"][0]
    assert top["dof"] == out["chi2"]["dof"] - top["rank"]
    if missing:
        assert out["proposed"].startswith("cyclic(j2,")
    else:
        assert not out["proposed"]


@pytest.mark.parametrize("data", ["touches", "ballbar"])
def test_refine_adds_the_shoulder_and_the_held_out_error_falls(ur10, shoulder, data):
    d, truth, q_new = shoulder
    start, refined = d / f"{data}-start.json", d / f"{data}-refined.json"
    validation = d / f"{data}-validation.csv"
    if data == "touches":
        write_touches(validation, ur10, truth, np.random.default_rng(8), PLANES, 5, TOUCH_MM)
    else:
        write_lengths(validation, ur10, truth, np.random.default_rng(8), PIVOTS_M, LENGTHS_MM,
                      arcs=3, per_arc=4, noise_mm=BAR_MM)
    assert main(_args(d, "identify", data, start)) == 0
    assert main(_args(d, "refine", data, refined, "--validation", str(validation))) == 0
    history = json.loads((d / f"{data}-refined_refine.json").read_text())
    added = [s["added"] for s in history["steps"] if s["added"]]
    assert added and added[0].startswith("cyclic(j2,")
    scale = data == "touches"  # touches do not see the scale: a similarity registration
    before = _held_out_mm(d, start, ur10, truth, q_new, scale)
    after = _held_out_mm(d, refined, ur10, truth, q_new, scale)
    cv = [s["cv_rms_mm"] for s in history["steps"]]
    valid = [s["validation_rms_mm"] for s in history["steps"]]
    print(f"{data}: held out at new configurations, after a "
          f"{'similarity' if scale else 'rigid'} registration: {before:.4f} → {after:.4f} mm; "
          f"cross-validated {cv[0]:.4f} → {cv[-1]:.4f} mm; validation {valid[0]:.4f} → "
          f"{valid[-1]:.4f} mm")
    assert after < 0.3 * before
    sigma = TOUCH_MM if data == "touches" else BAR_MM
    assert cv[-1] < 0.3 * cv[0] and cv[-1] > 0.8 * sigma  # held out: not below the noise
    # validation readings against the planes, the pivots, as the fitted readings place them
    assert valid[-1] < 0.3 * valid[0] and 0.5 * sigma < valid[-1] < 2 * sigma


def test_a_touch_off_its_plane_is_named_as_a_gross_error(ur10, tmp_path):
    """One touch 0.2 mm off the front face, a geometric truth: judged against the plane as
    the other touches place it, it is the one gross error, named with its plane."""
    write_touches(tmp_path / "touches.csv", ur10, _truth(ur10, ()), np.random.default_rng(17),
                  PLANES, PER_PLANE, TOUCH_MM, displaced=(40, 2e-4))
    (tmp_path / "tool.yaml").write_text("flange: tool0\nmarkers:\n  ball: [0.0, 0.0, 100.0]\n")
    assert main(_args(tmp_path, "diagnose", "touches", tmp_path / "d.json")) == 0
    out = json.loads((tmp_path / "d.json").read_text())
    assert [(o["pose"], o["plane"]) for o in out["outliers"]] == [("front-11", "front")]
    assert 0.15 < out["outliers"][0]["size_mm"] < 0.25
    assert "pose front-11, marker ball on plane front (line 42 of" in out["verdict"]
    assert "A touch off its plane" in out["verdict"]


def test_the_added_variable_plot_of_touches_shows_the_missing_effect(shoulder):
    """The joint direction is projected as a touch's residual is (along its plane's normal,
    less what the plane takes): the partial residual follows the fitted cyclic error."""
    from doe_calib import Robot, Tool
    from doe_calib.diagnosis import diagnose
    from doe_calib.diagnosis.added_variable import strongest_added_variables
    from doe_calib.estimation.identify import WHOLE, identify
    from doe_calib.io.csv_files import read_measurements
    from doe_calib.model.marker_model import build_model

    d, _, _ = shoulder
    robot = Robot.from_urdf(sim.ur10_urdf(), flange="tool0")
    tool = Tool.from_yaml(d / "tool.yaml")
    meas = read_measurements(d / "touches.csv", robot, tool, sigma=TOUCH_MM * 1e-3)
    model = build_model(robot, tool, MODEL)
    with pytest.warns(Warning):
        fit = identify(model, meas, settings=WHOLE)
    diagnosis = diagnose(model, meas, fit)
    plot = strongest_added_variables(diagnosis, model, meas, fit, top=1).plots[0]
    print(f"added-variable plot of touches: {plot.effect}, r = {plot.correlation:.3f}")
    assert plot.effect.startswith("cyclic(j2,") and plot.correlation > 0.95


@pytest.mark.parametrize("data", ["touches", "ballbar"])
def test_held_out_touches_and_lengths_are_scored_against_the_kept_ones(geometric, data):
    """The linearised cross-validation is the refit on each fold's kept readings, a held-out
    touch compared to its plane, a held-out length to its pivot, as the kept ones place
    them; each a single coordinate."""
    from doe_calib import Robot, Tool
    from doe_calib.diagnosis.cross_validation import cross_validated_rms, make_folds
    from doe_calib.diagnosis.held_out_contacts import held_out_errors
    from doe_calib.estimation.identify import WHOLE, identify, identify_quietly
    from doe_calib.estimation.weighted_residuals import marker_points
    from doe_calib.io.csv_files import read_measurements
    from doe_calib.model.marker_model import build_model

    d, _, _ = geometric
    robot = Robot.from_urdf(sim.ur10_urdf(), flange="tool0")
    sigma = (TOUCH_MM if data == "touches" else BAR_MM) * 1e-3
    tool = Tool.from_yaml(d / "tool.yaml")
    meas = read_measurements(d / f"{data}.csv", robot, tool, sigma=sigma)
    model = build_model(robot, tool, MODEL)
    with pytest.warns(Warning):
        fit = identify(model, meas, settings=WHOLE)
    folds = make_folds(meas, 5)
    assert "not scored" not in folds.description
    sq = 0.0
    for held in folds.held:
        refit = identify_quietly(model, meas.subset(~held), fit.parameters)
        e, scored = held_out_errors(meas, ~held, marker_points(model, meas,
                                                               refit.parameters.values))
        assert scored.all()
        sq += float(np.sum(e[held] ** 2))
    refitted = np.sqrt(sq / len(meas)) * 1e3  # one coordinate per reading
    linear = cross_validated_rms(model, meas, fit.parameters, folds)
    print(f"{data}: cross-validated {linear:.5f} mm linearised, {refitted:.5f} mm refitted")
    assert linear == pytest.approx(refitted, rel=0.05)
    assert 0.8 * sigma * 1e3 < linear < 2 * sigma * 1e3
