"""A new session: the tracker moved and the probe was remounted since the calibration.

Readings from ``independent_sim`` (Pinocchio); the validation session has its own
base pose (drawn independently) and markers shifted 1–2 mm on the flange.
"""
import json
from dataclasses import replace

import independent_sim as sim
from markered_robot import markered_robot
import numpy as np
import pytest

from doe_calib import build_model, examples
from doe_calib.cli import main
from doe_calib.estimation.identify import identify_quietly
from doe_calib.estimation.session import reregister
from doe_calib.io.csv_files import read_measurements

SIGMA_MM = 0.02
MARKERS = {"A": [0.15, 0.0, 0.08], "B": [-0.075, 0.13, 0.08], "C": [-0.075, -0.13, 0.08]}
SHIFT_MM = np.array([[1.2, -0.8, 0.5], [-1.0, 1.5, 0.0], [0.4, 0.9, -1.6]])
MODEL = "joint_offset+geometry+joint_compliance"


@pytest.fixture(scope="module")
def session(tmp_path_factory):
    """(result, model, validation Measurements, validation CSV path, the moved truth)."""
    tmp = tmp_path_factory.mktemp("session")
    chain, robot, tool = markered_robot(examples.ROBOT_URDF, "tool0", MARKERS)
    rng = np.random.default_rng(31)
    truth = sim.Truth.random(chain, np.array(list(MARKERS.values())), rng)
    q, w = sim.unloaded_and_loaded(chain, sim.random_configurations(chain, 40, rng), 50.0,
                                   [0.0, 0.0, 0.1])
    sim.write_campaign(tmp / "train.csv", chain, truth, q, w, list(MARKERS), SIGMA_MM, rng)
    model = build_model(robot, tool, MODEL)
    result = identify_quietly(model, read_measurements(tmp / "train.csv", robot, tool))
    moved = sim.Truth.random(chain, truth.markers, np.random.default_rng(32))
    moved = replace(truth, base_rotvec=moved.base_rotvec, base_position=moved.base_position,
                    markers=truth.markers + SHIFT_MM / 1000.0)
    q, w = sim.unloaded_and_loaded(chain, sim.random_configurations(chain, 15, rng), 50.0,
                                   [0.0, 0.0, 0.1])
    sim.write_campaign(tmp / "valid.csv", chain, moved, q, w, list(MARKERS), SIGMA_MM, rng)
    result.to_json(tmp / "result.json")
    return result, model, read_measurements(tmp / "valid.csv", robot, tool), tmp, moved, truth


def _noise_level(pred):
    """What the error per coordinate should be: σ and the predicted std, mm."""
    return float(np.sqrt(SIGMA_MM ** 2 + np.mean(pred.std_mm ** 2)))


def test_without_registration_the_error_is_huge_and_the_option_is_named(session):
    result, model, valid, *_ = session
    pred = result.predict(valid, model)
    assert pred.error(valid)["rms_3d_mm"] > 100.0
    assert pred.registration is None
    assert len(pred.notes) == 1 and "--register frame+tool" in pred.notes[0], pred.notes
    assert "remounted" in pred.notes[0]


def test_frame_and_tool_bring_the_error_to_the_noise(session):
    result, model, valid, _, moved, truth = session
    pred = result.predict(valid, model, register="frame+tool")
    reg = pred.registration
    assert reg.what == "frame+tool" and reg.converged
    level = _noise_level(pred)
    assert pred.error(valid)["rms_mm"] < 2.0 * level, (pred.error(valid), level)
    assert reg.after["rms_mm"] == pytest.approx(pred.error(valid)["rms_mm"])
    assert reg.before["rms_3d_mm"] > 100.0
    assert pred.notes == ()
    # the markers moved by the remount: each shift found within 0.2 mm (the fit's marker
    # error of the calibration is in both)
    for j, name in enumerate(MARKERS):
        assert reg.marker_shifts_mm[name] == pytest.approx(np.linalg.norm(SHIFT_MM[j]), abs=0.3)
    # the frame change is the rigid motion from the old to the new tracker placement
    turn = sim.pin.exp3(moved.base_rotvec) @ sim.pin.exp3(truth.base_rotvec).T
    angle = np.degrees(np.linalg.norm(sim.pin.log3(turn)))
    assert reg.frame_rotation_deg == pytest.approx(angle, abs=0.01)
    shift = np.linalg.norm(moved.base_position - truth.base_position) * 1000.0
    assert np.linalg.norm(reg.frame_shift_mm) == pytest.approx(shift, rel=0.01)
    assert "--register" not in reg.summary() and "markers moved" in reg.summary()


def test_frame_alone_leaves_the_remount_and_says_so(session):
    result, model, valid, *_ = session
    pred = result.predict(valid, model, register="frame")
    assert pred.registration.what == "frame" and pred.registration.marker_shifts_mm == {}
    assert pred.error(valid)["rms_mm"] > 5 * _noise_level(pred)
    assert pred.error(valid)["rms_3d_mm"] < 10.0           # the frame took the big part
    assert len(pred.notes) == 1 and "--register frame+tool" in pred.notes[0], pred.notes
    assert "remounted" in pred.notes[0]


def test_reregister_rejects_an_unknown_choice(session):
    result, model, valid, *_ = session
    with pytest.raises(Exception, match="frame\\+tool"):
        reregister(model, result.parameters, valid, "tool")


def test_cli_register_reports_and_without_names_the_option(session, capsys):
    _, _, _, tmp, *_ = session
    args = ["predict", "--result", str(tmp / "result.json"), "--data", str(tmp / "valid.csv")]
    assert main(args + ["--out", str(tmp / "p0.csv"), "--json"]) == 0
    out = json.loads(capsys.readouterr().out)
    assert out["registration"] is None and "--register frame+tool" in out["notes"][0]
    assert main(args + ["--out", str(tmp / "p1.csv")]) == 0
    text = capsys.readouterr().out
    assert "--register frame+tool" in text
    assert main(args + ["--out", str(tmp / "p2.csv"), "--register", "frame+tool"]) == 0
    text = capsys.readouterr().out
    assert "re-registered frame+tool" in text and "markers moved on the flange" in text
    assert main(args + ["--out", str(tmp / "p3.csv"), "--register", "frame+tool",
                        "--json"]) == 0
    out = json.loads(capsys.readouterr().out)
    reg = out["registration"]
    assert reg["what"] == "frame+tool" and reg["after"]["rms_3d_mm"] < 0.2
    assert out["error"]["rms_3d_mm"] == pytest.approx(reg["after"]["rms_3d_mm"])
    assert reg["before"]["rms_3d_mm"] > 100.0 and out["notes"] == []
