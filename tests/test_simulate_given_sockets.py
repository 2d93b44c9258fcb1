"""``doe-calib simulate`` of a contact design, and of sockets whose position is given.

``--design`` of a contact design (``design --sockets``) simulates its contacts as
``--template`` simulates its CSV: each logged q seats the true ball in its socket. A socket
of given position (``--sockets`` a plate's drawing, or x, y, z on a template's rows) is
where the truth's base transform puts the drawing's point (moved by a draw of its
``socket_sigma``: the plate as made); its rows carry the drawing's position.
"""
import csv

import numpy as np
import pytest

from doe_calib import Robot, Tool
from doe_calib.cli import main
from doe_calib.estimation.result import load_parameters
from doe_calib.examples import BALL_TOOL_YAML, ROBOT_URDF, SOCKETS_CSV
from doe_calib.io.csv_files import read_measurements
from doe_calib.model.evaluation import marker_positions
from doe_calib.model.marker_model import build_model

MODEL = "joint_offset+geometry"
#: The drawing of the example plate, m.
DRAWING = {"S1": [1.6, -0.5, 0.4], "S2": [2.0, 0.0, 0.4], "S3": [1.6, 0.5, 0.4]}


@pytest.fixture(scope="module")
def designed(tmp_path_factory):
    d = tmp_path_factory.mktemp("given_sockets")
    assert main(["design", "--robot", ROBOT_URDF, "--tool", BALL_TOOL_YAML, "--sockets",
                 SOCKETS_CSV, "--model", MODEL, "--poses", "30", "--orientations", "150",
                 "--sigma", "0.01", "--seed", "1", "--out", str(d / "contacts.json")]) == 0
    robot = Robot.from_urdf(ROBOT_URDF)
    tool = Tool.from_yaml(BALL_TOOL_YAML)
    return d, robot, tool, build_model(robot, tool, MODEL)


def _simulate(d, out, *more):
    return main(["simulate", "--robot", ROBOT_URDF, "--tool", BALL_TOOL_YAML, "--model", MODEL,
                 "--seed", "4", "--out", str(d / out), "--truth-out", str(d / f"{out}.json"),
                 *more])


def _true_balls(d, out, model, robot, tool):
    """The file ``out`` read back, and the truth's ball (m, frame of the readings) at its
    logged q."""
    meas = read_measurements(d / out, robot, tool, require_xyz=False)
    truth = load_parameters(d / f"{out}.json", model)
    return meas, truth, marker_positions(model, truth.values, meas.configurations)[
        meas.config, 0]


def test_a_contact_design_is_simulated_as_its_contacts(designed, capsys):
    d, robot, tool, model = designed
    assert _simulate(d, "unknown.csv", "--design", str(d / "contacts.json"),
                     "--sigma", "1e-9") == 0
    assert "30 socket contacts in 3 sockets of unknown position" in capsys.readouterr().out
    meas, _, ball = _true_balls(d, "unknown.csv", model, robot, tool)
    planned = read_measurements(d / "contacts.csv", robot, tool, require_xyz=False)
    assert meas.contact.all() and sorted(meas.socket_names) == ["S1", "S2", "S3"]
    assert meas.configurations.pose == planned.configurations.pose
    moved = np.degrees(np.abs(meas.configurations.q - planned.configurations.q)).max()
    assert 0.01 < moved < 5.0  # the true robot seats the ball at other q than the plan's
    for k in meas.sockets_used:
        at = ball[meas.socket == k]
        assert np.abs(at - at.mean(axis=0)).max() < 1e-9


def test_given_sockets_seat_the_ball_at_the_drawing_as_the_plate_is_placed(designed, capsys):
    d, robot, tool, model = designed
    (d / "exact.csv").write_text("socket,x,y,z\n" + "".join(
        f"{n},{x * 1e3},{y * 1e3},{z * 1e3}\n" for n, (x, y, z) in DRAWING.items()))
    assert _simulate(d, "given.csv", "--design", str(d / "contacts.json"), "--sockets",
                     str(d / "exact.csv"), "--tracker", "3,-2,1,0.1,0,0.2",
                     "--sigma", "1e-9") == 0
    assert "30 socket contacts in 3 sockets of given position" in capsys.readouterr().out
    meas, truth, ball = _true_balls(d, "given.csv", model, robot, tool)
    assert not meas.contact.any() and meas.socket_sigma is None  # readings of given points
    base = truth.values[model.nominal().index("base")]
    assert np.allclose(base, np.r_[0.003, -0.002, 0.001, np.radians([0.1, 0.0, 0.2])])
    for name, point in DRAWING.items():
        at = meas.socket == meas.socket_names.index(name)
        assert np.allclose(meas.xyz[at], point, atol=1e-12)  # the drawing, written
        assert np.abs(ball[at] - point).max() < 1e-9  # the true ball there, plate frame
    # in the robot's own frame the ball is elsewhere: the plate's placement matters
    unplaced = truth.values.copy()
    unplaced[model.nominal().index("base")] = 0.0
    own = marker_positions(model, unplaced, meas.configurations)[meas.config, 0]
    assert np.linalg.norm(own - meas.xyz, axis=1).min() > 1e-3


def test_a_drawing_tolerance_moves_each_socket_once(designed):
    d, robot, tool, model = designed
    assert _simulate(d, "drawn.csv", "--design", str(d / "contacts.json"), "--sockets",
                     SOCKETS_CSV, "--sigma", "1e-9") == 0
    meas, truth, ball = _true_balls(d, "drawn.csv", model, robot, tool)
    assert np.allclose(meas.socket_sigma, 5e-6)
    base = truth.values[model.nominal().index("base")]
    assert np.linalg.norm(base[:3]) < 0.02 and np.degrees(np.linalg.norm(base[3:])) < 1.0
    for name, point in DRAWING.items():
        at = ball[meas.socket == meas.socket_names.index(name)]
        assert np.abs(at - at.mean(axis=0)).max() < 1e-9  # one true point per socket
        assert 0.0 < np.linalg.norm(at[0] - point) < 5 * np.sqrt(3) * 5e-6


def test_a_template_with_given_positions(designed):
    """x, y, z on a template's socket rows: the truth seats the ball there (the plate, by
    default, placed near the robot's base frame, where the design put the sockets)."""
    d, robot, tool, model = designed
    with open(d / "contacts.csv", encoding="utf-8") as f:
        rows = list(csv.DictReader(line for line in f if not line.startswith("#")))
    with open(d / "template.csv", "w", newline="", encoding="utf-8") as f:
        out = csv.DictWriter(f, [*rows[0], "x", "y", "z"])
        out.writeheader()
        for row in rows:
            given = DRAWING[row["socket"]] if row["socket"] != "S3" else ["", "", ""]
            out.writerow({**row, **dict(zip("xyz", (v and v * 1e3 for v in given)))})
    assert _simulate(d, "mixed.csv", "--template", str(d / "template.csv"),
                     "--sigma", "1e-9") == 0  # the plate a few mm from the base frame
    meas, _, ball = _true_balls(d, "mixed.csv", model, robot, tool)
    s3 = meas.socket == meas.socket_names.index("S3")
    assert meas.contact.tolist() == s3.tolist()  # S3 unknown, the others given
    for name in ("S1", "S2"):
        at = meas.socket == meas.socket_names.index(name)
        assert np.abs(ball[at] - DRAWING[name]).max() < 1e-9


def test_sockets_refusals(designed, capsys):
    d, *_ = designed
    assert _simulate(d, "x.csv", "--sockets", SOCKETS_CSV) == 2
    assert "--sockets gives the positions of a template's sockets" in capsys.readouterr().err
    (d / "other.csv").write_text("socket,x,y,z\nS9,0,0,0\n")
    assert _simulate(d, "x.csv", "--design", str(d / "contacts.json"), "--sockets",
                     str(d / "other.csv")) != 0
    assert "socket 'S9': no contact of the template is seated in it" in \
        capsys.readouterr().err
    (d / "negative.csv").write_text("socket,x,y,z,socket_sigma\nS1,1600,-500,400,-1\n")
    assert _simulate(d, "x.csv", "--design", str(d / "contacts.json"), "--sockets",
                     str(d / "negative.csv")) != 0
    err = capsys.readouterr().err
    assert "line 2" in err and "socket_sigma '-1'" in err
    assert _simulate(d, "x.csv", "--design", str(d / "contacts.json"), "--load",
                     "5@0,0,50") == 2
    assert "--load is not taken with a contact design" in capsys.readouterr().err


def test_a_touch_design_is_simulated_as_its_touches(designed, capsys):
    """``--design`` of ``design --planes``: each logged q puts the true ball on its plane."""
    d, robot, tool, model = designed
    (d / "planes.csv").write_text("plane,x,y,z,nx,ny,nz,half\ntable,1800,0,400,0,0,1,400\n"
                                  "front,2200,0,700,-1,0,0,250\n"
                                  "slant,1700,-700,700,0,0.5,0.866,250\n")
    assert main(["design", "--robot", ROBOT_URDF, "--tool", BALL_TOOL_YAML, "--planes",
                 str(d / "planes.csv"), "--model", MODEL, "--poses", "60", "--orientations",
                 "150", "--sigma", "0.01", "--seed", "1", "--out", str(d / "touches.json")]) == 0
    capsys.readouterr()
    assert _simulate(d, "touched.csv", "--design", str(d / "touches.json"),
                     "--sigma", "1e-9") == 0
    assert "60 touches of 3 planes" in capsys.readouterr().out
    meas, _, ball = _true_balls(d, "touched.csv", model, robot, tool)
    assert meas.touch.all()
    for k in meas.planes_used:
        at = ball[meas.plane == k]
        centred = at - at.mean(axis=0)
        assert np.linalg.svd(centred, compute_uv=False)[-1] < 1e-8  # all on one plane
