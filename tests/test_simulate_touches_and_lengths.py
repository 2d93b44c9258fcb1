"""``doe-calib simulate --template`` on plane touches and ballbar lengths (issue #31).

The templates are campaigns planned on the nominal UR10 (by the independent simulator): a
table top and two faces of a block touched 20 times each; arcs about two pivots at 150, 225
and 300 mm. Simulated on a random truth, a touch's logged q is the one that puts the *true*
ball on its plane; a ballbar reading keeps its planned q and logs the true ball's distance
from the pivot. ``identify`` on what simulate writes then recovers the truth as far as each
instrument sees: touches all but a rigid motion and the scale (a similarity registration),
lengths all but a rigid motion (a rigid registration).
"""
import independent_sim as sim
import numpy as np
import pytest
from seated_contacts import write_lengths, write_touches

from doe_calib import Robot, Tool
from doe_calib.cli import main
from doe_calib.errors import DataError
from doe_calib.estimation.ballbar import pivot_point
from doe_calib.estimation.planes import fitted_plane
from doe_calib.estimation.result import load_parameters
from doe_calib.io.csv_files import read_measurements
from doe_calib.io.measurements import Configurations
from doe_calib.model.evaluation import marker_positions
from doe_calib.model.marker_model import build_model
from doe_calib.model.seating import simulate_readings

BALL_M = np.array([0.0, 0.0, 0.10])
MODEL = "joint_offset+geometry"
PLANES = {"table": ([0.3, 0.0, 0.05], [1, 0, 0], [0, 1, 0], 0.45),
          "front": ([0.75, 0.0, 0.35], [0, 1, 0], [0, 0, 1], 0.2),
          "slant": ([0.1, -0.7, 0.35], [1, 0, 0], [0, 1 / np.sqrt(2), 1 / np.sqrt(2)], 0.2)}
PIVOTS_M = {"P1": [0.55, 0.30, 0.05], "P2": [0.20, -0.65, 0.05]}


@pytest.fixture(scope="module")
def planned(ur10, tmp_path_factory):
    d = tmp_path_factory.mktemp("simulate_touches")
    nominal = sim.Truth.nominal(ur10, BALL_M[None])
    write_touches(d / "touches.csv", ur10, nominal, np.random.default_rng(5), PLANES, 20,
                  scatter_mm=0.0)
    write_lengths(d / "ballbar.csv", ur10, nominal, np.random.default_rng(6), PIVOTS_M,
                  (150.0, 225.0, 300.0), noise_mm=0.0)
    (d / "tool.yaml").write_text("flange: tool0\nmarkers:\n  ball: [0.0, 0.0, 100.0]\n")
    robot = Robot.from_urdf(sim.ur10_urdf(), flange="tool0")
    tool = Tool.from_yaml(d / "tool.yaml")
    return d, robot, tool, build_model(robot, tool, MODEL)


def _simulate(d, template, out, sigma, truth_out):
    return main(["simulate", "--robot", str(sim.ur10_urdf()), "--tool", str(d / "tool.yaml"),
                 "--model", MODEL, "--template", str(d / template), "--seed", "4",
                 "--sigma", str(sigma), "--out", str(d / out), "--truth-out",
                 str(d / truth_out)])


def _true_balls(model, truth, meas):
    return marker_positions(model, truth.values, meas.configurations)[meas.config, meas.marker]


def test_touches_are_logged_where_the_true_ball_lies_on_its_plane(planned, capsys):
    d, robot, tool, model = planned
    assert _simulate(d, "touches.csv", "exact.csv", 1e-9, "truth.json") == 0
    assert "60 touches of 3 planes" in capsys.readouterr().out
    template = read_measurements(d / "touches.csv", robot, tool, require_xyz=False)
    meas = read_measurements(d / "exact.csv", robot, tool)
    assert meas.touch.all() and meas.plane_names == template.plane_names
    ball = _true_balls(model, load_parameters(d / "truth.json", model), meas)
    moved = np.degrees(np.abs(meas.configurations.q - template.configurations.q)).max()
    assert 0.001 < moved < 5.0  # the truth puts the ball on the plane at other q
    for k in meas.planes_used:
        at = ball[meas.plane == k]
        centre, axes, _ = fitted_plane(at, np.ones(len(at)))
        assert np.abs((at - centre) @ axes[2]).max() < 1e-9  # every touch on one plane


def test_lengths_are_the_true_distances_at_the_planned_q(planned, capsys):
    d, robot, tool, model = planned
    assert _simulate(d, "ballbar.csv", "exact-bar.csv", 1e-9, "truth-bar.json") == 0
    assert "; 96 ballbar lengths from 2 pivots)" in capsys.readouterr().out
    template = read_measurements(d / "ballbar.csv", robot, tool, require_xyz=False)
    meas = read_measurements(d / "exact-bar.csv", robot, tool)
    assert np.array_equal(meas.configurations.q, template.configurations.q)
    ball = _true_balls(model, load_parameters(d / "truth-bar.json", model), meas)
    for k in meas.sockets_used:
        at = meas.socket == k
        s = pivot_point(ball[at], meas.distance[at], np.ones(int(at.sum())))
        assert np.abs(np.linalg.norm(ball[at] - s, axis=1) - meas.distance[at]).max() < 1e-9
    assert np.abs(meas.distance - template.distance).max() > 1e-5  # not the plan's lengths


def _registered_rms_mm(predicted, true, scale):
    a, b = predicted - predicted.mean(0), true - true.mean(0)
    u, s, vt = np.linalg.svd(a.T @ b)
    d = np.diag([1.0, 1.0, np.sign(np.linalg.det(u @ vt))])
    rot = (u @ d @ vt).T
    grow = np.trace(np.diag(s) @ d) / np.sum(a * a) if scale else 1.0
    return float(np.sqrt(np.mean(np.sum((grow * a @ rot.T - b) ** 2, axis=1))) * 1e3)


@pytest.mark.parametrize("data, sigma, limit", [("touches", 0.01, 0.05),
                                                ("ballbar", 0.001, 0.03)])
def test_identify_recovers_the_truth_from_simulated_files(planned, tmp_path, data, sigma,
                                                          limit):
    d, robot, tool, model = planned
    assert _simulate(d, f"{data}.csv", f"sim-{data}.csv", sigma, f"truth-{data}.json") == 0
    assert main(["identify", "--robot", str(sim.ur10_urdf()), "--tool", str(d / "tool.yaml"),
                 "--data", str(d / f"sim-{data}.csv"), "--model", MODEL, "--sigma", str(sigma),
                 "--out", str(tmp_path / "r.json")]) == 0
    truth = load_parameters(d / f"truth-{data}.json", model)
    fitted = load_parameters(tmp_path / "r.json", model)
    new = Configurations.from_arrays(np.random.default_rng(2).uniform(-np.pi, np.pi, (40, 6)))
    true = marker_positions(model, truth.values, new)[:, 0]
    scale = data == "touches"  # touches do not see the scale
    before = _registered_rms_mm(marker_positions(model, model.nominal().values, new)[:, 0],
                                true, scale)
    after = _registered_rms_mm(marker_positions(model, fitted.values, new)[:, 0], true, scale)
    print(f"simulated {data}: nominal {before:.3f} mm, identified {after:.4f} mm "
          f"({'similarity' if scale else 'rigid'} registration)")
    assert before > 1.0 and after < limit


def test_given_planes_must_name_every_plane(planned):
    d, robot, tool, model = planned
    template = read_measurements(d / "touches.csv", robot, tool, require_xyz=False)
    with pytest.raises(DataError, match="no plane given for plane 'front'"):
        simulate_readings(model, model.nominal(), template, 1e-5,
                          planes={"table": (np.zeros(3), np.array([0.0, 0.0, 1.0]))})
