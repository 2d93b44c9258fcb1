"""``doe-calib simulate --template``: socket contacts written as the true robot seats them.

The template is a contact campaign planned on the nominal UR10 (its q seat the nominal
ball; seated by the independent simulator). Simulated on a random truth, each contact's
logged q must be the one that puts the *true* ball in its socket; ``identify`` on what
simulate writes then recovers the truth as far as contacts can see (all but a rigid
motion and the scale: compared after a similarity registration).
"""
import csv

import independent_sim as sim
import numpy as np
import pytest
from seated_contacts import q_columns, write_contacts

from doe_calib import Robot, Tool
from doe_calib.cli import main
from doe_calib.errors import DataError
from doe_calib.estimation.result import load_parameters
from doe_calib.io.csv_files import read_measurements
from doe_calib.io.measurements import Configurations
from doe_calib.model.evaluation import marker_positions
from doe_calib.model.marker_model import build_model
from doe_calib.model.seating import seated_configurations, simulate_readings

BALL_M = np.array([0.0, 0.0, 0.10])
SOCKETS_M = {"S1": [0.65, 0.25, 0.05], "S2": [0.45, -0.55, 0.05], "S3": [-0.25, 0.70, 0.05]}
MODEL = "joint_offset+geometry"


@pytest.fixture(scope="module")
def planned(ur10, tmp_path_factory):
    d = tmp_path_factory.mktemp("simulate_contacts")
    write_contacts(d / "template.csv", ur10, sim.Truth.nominal(ur10, BALL_M[None]),
                   np.random.default_rng(5), SOCKETS_M, 15, scatter_mm=0.0)
    (d / "tool.yaml").write_text("flange: tool0\nmarkers:\n  ball: [0.0, 0.0, 100.0]\n")
    robot = Robot.from_urdf(sim.ur10_urdf(), flange="tool0")
    tool = Tool.from_yaml(d / "tool.yaml")
    return d, robot, tool, build_model(robot, tool, MODEL)


def _simulate(d, out, *more):
    return main(["simulate", "--robot", str(sim.ur10_urdf()), "--tool", str(d / "tool.yaml"),
                 "--model", MODEL, "--template", str(d / "template.csv"), "--seed", "4",
                 "--out", str(d / out), *more])


def test_contacts_are_logged_where_the_true_ball_sits_in_its_socket(planned):
    d, robot, tool, model = planned
    assert _simulate(d, "exact.csv", "--sigma", "1e-9", "--truth-out",
                     str(d / "truth.json")) == 0
    template = read_measurements(d / "template.csv", robot, tool, require_xyz=False)
    meas = read_measurements(d / "exact.csv", robot, tool)
    assert meas.contact.all() and meas.socket_names == template.socket_names
    truth = load_parameters(d / "truth.json", model)
    ball = marker_positions(model, truth.values, meas.configurations)[meas.config, 0]
    moved = np.degrees(np.abs(meas.configurations.q - template.configurations.q)).max()
    assert 0.01 < moved < 5.0  # the truth seats the ball at other q than the plan's
    for k in meas.sockets_used:
        at = ball[meas.socket == k]
        assert np.abs(at - at.mean(axis=0)).max() < 1e-9  # every contact in one point


def test_identify_recovers_the_truth_from_simulated_contacts(planned, tmp_path):
    d, robot, tool, model = planned
    assert _simulate(d, "contacts.csv", "--sigma", "0.01", "--truth-out",
                     str(d / "truth2.json")) == 0
    assert main(["identify", "--robot", str(sim.ur10_urdf()), "--tool", str(d / "tool.yaml"),
                 "--data", str(d / "contacts.csv"), "--model", MODEL, "--sigma", "0.01",
                 "--out", str(tmp_path / "r.json")]) == 0
    truth = load_parameters(d / "truth2.json", model)
    fitted = load_parameters(tmp_path / "r.json", model)
    q = np.random.default_rng(2).uniform(-np.pi, np.pi, (40, 6))
    new = Configurations.from_arrays(q)
    true = marker_positions(model, truth.values, new)[:, 0]
    before = _similarity_rms_mm(marker_positions(model, model.nominal().values, new)[:, 0],
                                true)
    after = _similarity_rms_mm(marker_positions(model, fitted.values, new)[:, 0], true)
    print(f"simulated contacts: nominal {before:.3f} mm, identified {after:.4f} mm "
          f"(similarity registration)")
    assert before > 1.0 and after < 0.03


def _similarity_rms_mm(predicted, true):
    a, b = predicted - predicted.mean(0), true - true.mean(0)
    u, s, vt = np.linalg.svd(a.T @ b)
    d = np.diag([1.0, 1.0, np.sign(np.linalg.det(u @ vt))])
    rot = (u @ d @ vt).T
    grow = np.trace(np.diag(s) @ d) / np.sum(a * a)
    return float(np.sqrt(np.mean(np.sum((grow * a @ rot.T - b) ** 2, axis=1))) * 1e3)


def test_tracker_rows_of_a_template_are_simulated_at_their_q(planned, tmp_path):
    """A template mixing tracker rows and contacts: the tracker rows keep their q and get
    x, y, z; the written file reads back with its sockets."""
    d, robot, tool, model = planned
    lines = (d / "template.csv").read_text().splitlines()
    q = np.random.default_rng(8).uniform(-np.pi, np.pi, (3, 6))
    lines[0] += ",x,y,z"
    lines[1:] = [line + ",,," for line in lines[1:]]
    lines += [",".join([f"t{i}", *q_columns(qi).values(), "ball", "", "", "", ""])
              for i, qi in enumerate(q)]
    (tmp_path / "mixed.csv").write_text("\n".join(lines) + "\n")
    template = read_measurements(tmp_path / "mixed.csv", robot, tool, require_xyz=False)
    truth = model.nominal()
    meas = simulate_readings(model, truth, template, 1e-5, np.random.default_rng(1))
    tracked = ~meas.contact
    assert tracked.sum() == 3 and np.isfinite(meas.xyz[tracked]).all()
    assert np.isnan(meas.xyz[meas.contact]).all()
    rows = meas.config[tracked]
    assert np.array_equal(meas.configurations.q[rows], template.configurations.q[rows])
    from doe_calib.io.csv_files import write_measurements

    write_measurements(tmp_path / "out.csv", meas, robot, tool)
    back = read_measurements(tmp_path / "out.csv", robot, tool)
    assert back.socket.tolist() == meas.socket.tolist()
    with open(tmp_path / "out.csv") as f:
        row = next(csv.DictReader(line for line in f if not line.startswith("#")))
    assert row["socket"] == "S1" and row["x"] == ""


def test_an_unreachable_socket_is_refused_with_its_pose(planned):
    d, robot, tool, model = planned
    template = read_measurements(d / "template.csv", robot, tool, require_xyz=False)
    far = np.full((len(template), 3), 5.0)  # 5 m away: out of the UR10's reach
    with pytest.raises(DataError, match=r"line \d+: pose S\d-\d+: the true robot cannot "
                                        r"seat its ball in socket S\d"):
        seated_configurations(model, model.nominal().values, template, far)


def test_template_refuses_design_options(planned, capsys):
    d, *_ = planned
    assert _simulate(d, "x.csv", "--load", "5@0,0,50") == 2
    assert "--load is not taken with --template" in capsys.readouterr().err


def test_given_socket_points_must_name_every_socket(planned):
    d, robot, tool, model = planned
    template = read_measurements(d / "template.csv", robot, tool, require_xyz=False)
    with pytest.raises(DataError, match="no point given for socket 'S2'"):
        simulate_readings(model, model.nominal(), template, 1e-5,
                          points={"S1": np.zeros(3), "S3": np.zeros(3)})
