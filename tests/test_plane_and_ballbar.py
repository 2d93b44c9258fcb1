"""Plane touches and ballbar lengths (formats.md §3, *Plane touches*, *Ballbar and gauge
lengths*) through ``identify`` and ``predict``, judged on campaigns simulated independently
of our model (issue #31).

The truth is that of tests/test_socket_contacts.py (a UR10 with placement errors up to
0.5 mm / 0.05° on every joint, joint offsets up to 0.1°, the ball centre 1 mm off
nominal); each contact is reached by IK on the true robot from a random start (a varied
tool orientation) and only the controller's joint values are written. Plane touches: a
table top and two faces of a block, 20 touches each, scatter 0.01 mm along the normal.
Ballbar: two pivots on the table, lengths 150, 225 and 300 mm read to 0.001 mm, arcs of
poses; one pivot also takes seated contacts.
"""
import csv

import independent_sim as sim
import numpy as np
import pytest

from doe_calib import Robot, Tool
from doe_calib.cli import main
from doe_calib.errors import DataError
from doe_calib.io.csv_files import read_measurements

BALL_M = np.array([0.0, 0.0, 0.10])  # nominal ball centre, flange frame
TOUCH_MM, BAR_MM, SEATING_MM = 0.01, 0.001, 0.01
#: Each plane: a point on it, two in-plane axes (half-extents in them, m): a table top and
#: two faces of a block, one upright, one slanted.
PLANES = {"table": ([0.3, 0.0, 0.05], [1, 0, 0], [0, 1, 0], 0.45),
          "front": ([0.75, 0.0, 0.35], [0, 1, 0], [0, 0, 1], 0.2),
          "slant": ([0.1, -0.7, 0.35], [1, 0, 0], [0, 1 / np.sqrt(2), 1 / np.sqrt(2)], 0.2)}
PIVOTS_M = {"P1": [0.55, 0.30, 0.05], "P2": [0.20, -0.65, 0.05]}
LENGTHS_MM = (150.0, 225.0, 300.0)


@pytest.fixture(scope="module")
def truth(ur10):
    return sim.ball_on_stem_truth(ur10)


def _ball(ur10, truth, q):
    """True ball centre (3,), m, at commanded q (N,) (the robot's root frame)."""
    return sim.marker_positions(ur10, truth, q[None], np.zeros((1, 6)))[0, 0]


def _reach(ur10, truth, target, rng):
    """Commanded q that puts the true ball centre on ``target``, by damped Gauss–Newton on
    position from a random start (a varied tool orientation), or None."""
    q = rng.uniform(-np.pi, np.pi, 6)
    for _ in range(60):
        e = target - _ball(ur10, truth, q)
        if np.linalg.norm(e) < 1e-12:
            return (q + np.pi) % (2 * np.pi) - np.pi  # inside every joint's limits
        jac = np.array([(_ball(ur10, truth, q + h) - _ball(ur10, truth, q - h)) / 2e-7
                        for h in np.eye(6) * 1e-7]).T
        q = q + jac.T @ np.linalg.solve(jac @ jac.T + 1e-6 * np.eye(3), e)
    return None


def _row(pose, q, **cells):
    return {"pose": pose, **{f"q{k + 1}": repr(float(v)) for k, v in enumerate(np.degrees(q))},
            "marker": "ball", **cells}


def _write(path, rows):
    names = list(dict.fromkeys(k for r in rows for k in r))
    with open(path, "w", newline="") as f:
        writer = csv.DictWriter(f, fieldnames=names, restval="")
        writer.writeheader()
        writer.writerows(rows)


def _touches(ur10, truth, rng, per_plane: int = 20) -> list:
    rows = []
    for name, (point, e1, e2, half) in PLANES.items():
        e1, e2 = np.asarray(e1, float), np.asarray(e2, float)
        normal = np.cross(e1, e2)
        while sum(r["plane"] == name for r in rows) < per_plane:
            a, b = rng.uniform(-half, half, 2)
            target = np.asarray(point) + a * e1 + b * e2 + \
                normal * rng.normal(scale=TOUCH_MM * 1e-3)
            q = _reach(ur10, truth, target, rng)
            if q is not None:
                rows.append(_row(f"{name}-{len(rows)}", q, plane=name))
    return rows


def _ballbar(ur10, truth, rng) -> list:
    """Arcs of poses about each pivot: six azimuths, elevation 15° … 75°, each arc at one of
    the lengths; P1 also takes 6 seated contacts."""
    rows = []
    for name, pivot in PIVOTS_M.items():
        for arc, azimuth in enumerate(np.radians(np.arange(0, 360, 60)) + rng.uniform(0, 1)):
            length = LENGTHS_MM[arc % 3]
            for elevation in np.radians(np.linspace(15, 75, 8)):
                d = np.array([np.cos(azimuth) * np.cos(elevation),
                              np.sin(azimuth) * np.cos(elevation), np.sin(elevation)])
                q = _reach(ur10, truth, np.asarray(pivot) + length * 1e-3 * d, rng)
                if q is None:
                    continue
                true = np.linalg.norm(_ball(ur10, truth, q) - pivot) * 1e3
                rows.append(_row(f"{name}-{len(rows)}", q, socket=name,
                                 distance=repr(float(true + rng.normal(scale=BAR_MM))),
                                 sigma=repr(BAR_MM)))
    seated = 0
    while seated < 6:
        target = np.asarray(PIVOTS_M["P1"]) + rng.normal(scale=SEATING_MM * 1e-3, size=3)
        q = _reach(ur10, truth, target, rng)
        if q is not None:
            seated += 1
            rows.append(_row(f"seat-{seated}", q, socket="P1", sigma=repr(SEATING_MM)))
    return rows


@pytest.fixture(scope="module")
def campaigns(ur10, truth, tmp_path_factory):
    rng = np.random.default_rng(17)
    d = tmp_path_factory.mktemp("planes")
    _write(d / "touches.csv", _touches(ur10, truth, rng))
    _write(d / "ballbar.csv", _ballbar(ur10, truth, rng))
    (d / "tool.yaml").write_text("flange: tool0\nmarkers:\n  ball: [0.0, 0.0, 100.0]\n")
    q_new = rng.uniform(-np.pi, np.pi, (40, 6))
    _write(d / "new.csv", [_row(str(i), q) for i, q in enumerate(q_new)])
    return d, q_new


def _robot_tool(d):
    return Robot.from_urdf(sim.ur10_urdf(), flange="tool0"), Tool.from_yaml(d / "tool.yaml")


def _registered_rms_mm(predicted, true, scale: bool = False):
    """3-D RMS (mm) of ``predicted`` − ``true`` (K, 3), m, after the best rigid motion
    (Kabsch) of the predicted points onto the true ones; with ``scale``, the best similarity
    (Umeyama: a uniform scale too)."""
    a, b = predicted - predicted.mean(0), true - true.mean(0)
    u, s, vt = np.linalg.svd(a.T @ b)
    d = np.diag([1.0, 1.0, np.sign(np.linalg.det(u @ vt))])
    rot = (u @ d @ vt).T
    grow = np.trace(np.diag(s) @ d) / np.sum(a * a) if scale else 1.0
    return float(np.sqrt(np.mean(np.sum((grow * a @ rot.T - b) ** 2, axis=1))) * 1e3)


def _identify_and_predict(d, data, sigma_mm, capsys):
    """``identify`` on ``data`` then ``predict`` at the new configurations: (what identify
    said, the predicted points (40, 3), m)."""
    out = d / f"{data}.json"
    assert main(["identify", "--robot", str(sim.ur10_urdf()), "--tool", str(d / "tool.yaml"),
                 "--data", str(d / f"{data}.csv"), "--sigma", str(sigma_mm),
                 "--model", "joint_offset+geometry", "--out", str(out)]) == 0
    said = capsys.readouterr()
    assert main(["predict", "--result", str(out), "--data", str(d / "new.csv"),
                 "--out", str(d / f"{data}-pred.csv")]) == 0
    with open(d / f"{data}-pred.csv") as f:
        pred = np.array([[float(r[c]) for c in "xyz"] for r in
                         csv.DictReader(line for line in f if not line.startswith("#"))])
    return said.out + said.err, pred / 1e3


def _before(ur10, q_new, true):
    nominal = sim.Truth.nominal(ur10, BALL_M[None])
    return _registered_rms_mm(sim.marker_positions(ur10, nominal, q_new,
                                                   np.zeros((40, 6)))[:, 0], true)


def test_touches_and_lengths_are_read(campaigns):
    d, _ = campaigns
    robot, tool = _robot_tool(d)
    touches = read_measurements(d / "touches.csv", robot, tool, sigma=1e-5)
    assert touches.plane_names == ("table", "front", "slant") and touches.touch.all()
    assert touches.n_coordinates == 60 - 9  # one per touch, less 3 per plane
    bar = read_measurements(d / "ballbar.csv", robot, tool, sigma=1e-6)
    n_bar = int(bar.ballbar.sum())
    assert bar.socket_names == ("P1", "P2") and bar.contact.all() and n_bar > 80
    assert bar.n_coordinates == n_bar + 3 * 6 - 6  # a length each, 3 per seated contact


def test_plane_campaign_predicts_new_configurations(ur10, truth, campaigns, capsys):
    d, q_new = campaigns
    said, pred = _identify_and_predict(d, "touches", TOUCH_MM, capsys)
    assert "plane touches cannot see the robot's base pose" in said
    true = sim.marker_positions(ur10, truth, q_new, np.zeros((40, 6)))[:, 0]
    before, after = _before(ur10, q_new, true), _registered_rms_mm(pred, true)
    similar = _registered_rms_mm(pred, true, scale=True)
    print(f"planes: nominal {before:.3f} mm; identified {after:.4f} mm (rigid), "
          f"{similar:.4f} mm (similarity)")
    assert before > 1.0
    assert similar <= 0.05  # what touches see: all but a rigid motion and the scale
    assert after <= 0.2  # the scale rides on the link length held at the URDF's


def test_ballbar_campaign_predicts_new_configurations(ur10, truth, campaigns, capsys):
    d, q_new = campaigns
    said, pred = _identify_and_predict(d, "ballbar", BAR_MM, capsys)
    assert "ballbar readings cannot see the robot's base pose" in said
    assert "cannot see the robot's scale" not in said
    true = sim.marker_positions(ur10, truth, q_new, np.zeros((40, 6)))[:, 0]
    before, after = _before(ur10, q_new, true), _registered_rms_mm(pred, true)
    print(f"ballbar: nominal {before:.3f} mm; identified {after:.4f} mm (rigid)")
    assert before > 1.0
    assert after <= 0.03  # the lengths see the scale: only a rigid motion is left


def test_a_table_alone_cannot_see_the_shoulder_offset(campaigns):
    """Touches of the table top alone (normal along the first joint's axis) cannot see the
    shoulder's offset from that axis, nor a shift along the parallel joints' axes: each moves
    every touch parallel to the table. Three planes see them."""
    from doe_calib.estimation.preparation import (
        WITHIN_PLANES,
        fix_unseen_by_contacts,
        fix_unseen_by_touches,
    )
    from doe_calib.model.marker_model import build_model

    d, _ = campaigns
    robot, tool = _robot_tool(d)
    meas = read_measurements(d / "touches.csv", robot, tool, sigma=TOUCH_MM * 1e-3)
    model = build_model(robot, tool, "joint_offset+geometry")
    start = fix_unseen_by_contacts(robot, model.nominal(), ["plane"])

    def unseen(readings):
        params = fix_unseen_by_touches(model, readings, start)
        return {n for n, why in zip(params.names, params.fixed_reason) if why == WITHIN_PLANES}
    table = unseen(meas.subset(meas.plane == meas.plane_names.index("table")))
    assert {"g_shoulder_lift_joint_ty", "g_shoulder_lift_joint_tz", "g_elbow_joint_ty",
            "g_wrist_1_joint_ty", "g_wrist_2_joint_ty"} <= table
    assert unseen(meas) == set()


@pytest.mark.parametrize("data, sigma", [("touches", TOUCH_MM), ("ballbar", BAR_MM)])
def test_jacobian_matches_finite_differences(campaigns, data, sigma):
    """The projected Jacobian against central differences of the eliminated residuals: the
    gradient of ‖r‖² exactly (variable projection), the residuals to the order of the
    residuals (Kaufman's approximation) once the fit has brought them down."""
    from doe_calib.estimation.identify import FitSettings, identify
    from doe_calib.estimation.weighted_residuals import weighted_residual
    from doe_calib.model.marker_model import build_model

    d, _ = campaigns
    robot, tool = _robot_tool(d)
    meas = read_measurements(d / f"{data}.csv", robot, tool, sigma=sigma * 1e-3)
    model = build_model(robot, tool, "joint_offset+geometry")
    nominal = model.nominal().values
    h = 1e-7

    def differences(values, f):
        return np.array([(f(values + e) - f(values - e)) / (2 * h)
                         for e in np.eye(len(values)) * h]).T

    r, jac = weighted_residual(model, meas, nominal)
    grad = differences(nominal, lambda v: np.sum(weighted_residual(model, meas, v, False)[0]
                                                 ** 2))
    assert np.allclose(grad, 2 * jac.T @ r, rtol=1e-5, atol=1e-6 * np.abs(grad).max())
    with pytest.warns(Warning):
        fitted = identify(model, meas, settings=FitSettings(select="none")).parameters.values
    r, jac = weighted_residual(model, meas, fitted)
    numeric = differences(fitted, lambda v: weighted_residual(model, meas, v, False)[0])
    assert np.abs(numeric - jac).max() <= 1e-3 * np.abs(jac).max()


def _bad(d, tmp_path, name, edit):
    lines = (d / name).read_text().splitlines()
    bad = tmp_path / "bad.csv"
    bad.write_text("\n".join(edit(lines)) + "\n")
    return bad


def test_a_plane_of_three_touches_is_refused(campaigns, tmp_path):
    d, _ = campaigns
    robot, tool = _robot_tool(d)

    def three_on_front(lines):
        front = [i for i, line in enumerate(lines) if line.startswith("front-")]
        return [line for i, line in enumerate(lines) if i not in front[3:]]
    bad = _bad(d, tmp_path, "touches.csv", three_on_front)
    with pytest.raises(DataError, match=r"bad.csv, line \d+, column 'plane' \(\d+\): plane "
                                        r"'front' has 3 touches"):
        read_measurements(bad, robot, tool, sigma=1e-5)


def test_a_distance_without_socket_is_refused(campaigns, tmp_path):
    d, _ = campaigns
    robot, tool = _robot_tool(d)

    def drop_socket(lines):
        k = lines[0].split(",").index("socket")
        cells = lines[3].split(",")
        cells[k] = ""
        return lines[:3] + [",".join(cells)] + lines[4:]
    bad = _bad(d, tmp_path, "ballbar.csv", drop_socket)
    with pytest.raises(DataError, match=r"bad.csv, line 4, column 'distance' \(\d+\): distance "
                                        r"without a socket"):
        read_measurements(bad, robot, tool, sigma=1e-6)


def test_a_negative_distance_is_refused(campaigns, tmp_path):
    d, _ = campaigns
    robot, tool = _robot_tool(d)

    def negative(lines):
        k = lines[0].split(",").index("distance")
        cells = lines[2].split(",")
        cells[k] = "-" + cells[k]
        return lines[:2] + [",".join(cells)] + lines[3:]
    with pytest.raises(DataError, match=r"bad.csv, line 3, column 'distance' \(\d+\): distance "
                                        r"-\d+.*mm: a ballbar's length is positive"):
        read_measurements(_bad(d, tmp_path, "ballbar.csv", negative), robot, tool, sigma=1e-6)


@pytest.mark.parametrize("data", ["touches", "ballbar"])
def test_touches_and_lengths_write_back_as_read(campaigns, tmp_path, data):
    from doe_calib.io.csv_files import write_measurements

    d, _ = campaigns
    robot, tool = _robot_tool(d)
    meas = read_measurements(d / f"{data}.csv", robot, tool)
    write_measurements(tmp_path / "back.csv", meas, robot, tool)
    back = read_measurements(tmp_path / "back.csv", robot, tool)
    for field in ("socket", "plane", "distance", "sigma", "xyz"):
        a, b = getattr(meas, field), getattr(back, field)
        assert (a is None and b is None) or np.array_equal(a, b, equal_nan=True), field
    assert (back.socket_names, back.plane_names) == (meas.socket_names, meas.plane_names)


def test_touches_mix_with_tracker_readings(ur10, truth, campaigns, tmp_path):
    """Tracker readings of the ball (base 2 m away, turned) and the touches in one file: the
    base is fitted from the tracker rows, the planes lie where they are in the tracker frame,
    and new configurations are predicted there with no registration."""
    from dataclasses import replace

    import pinocchio as pin

    from doe_calib.estimation.identify import FitSettings, identify
    from doe_calib.io.measurements import Configurations
    from doe_calib.model.marker_model import build_model

    d, q_new = campaigns
    rot = pin.exp3(np.array([0.3, -0.2, 1.9]))
    placed = replace(truth, base_rotvec=pin.log3(rot), base_position=np.array([2.0, -0.5, 0.3]))
    rng = np.random.default_rng(3)
    q = rng.uniform(-np.pi, np.pi, (20, 6))
    x = sim.marker_positions(ur10, placed, q, np.zeros((20, 6)))[:, 0]
    x = (x + rng.normal(scale=TOUCH_MM * 1e-3, size=x.shape)) * 1e3
    with open(d / "touches.csv") as f:
        rows = list(csv.DictReader(f))
    rows += [_row(f"t{i}", qi, **dict(zip("xyz", map(repr, map(float, xi)))))
             for i, (qi, xi) in enumerate(zip(q, x))]
    _write(tmp_path / "mixed.csv", rows)
    robot, tool = _robot_tool(d)
    meas = read_measurements(tmp_path / "mixed.csv", robot, tool, sigma=TOUCH_MM * 1e-3)
    assert meas.touch.sum() == 60 and (~meas.contact).sum() == 20
    assert meas.n_coordinates == 60 - 9 + 3 * 20
    model = build_model(robot, tool, "joint_offset+geometry")
    result = identify(model, meas, settings=FitSettings(select="none"))
    assert not any("touches cannot see" in n for n in result.warnings)
    predicted = result.predict(Configurations.from_arrays(q_new), model).xyz
    true = sim.marker_positions(ur10, placed, q_new, np.zeros((40, 6)))[:, 0]
    rms = np.sqrt(np.mean(np.sum((predicted - true) ** 2, axis=1))) * 1e3
    print(f"touches and tracker: {rms:.4f} mm at new configurations, tracker frame, "
          f"no registration")
    assert rms < 0.03


def test_pivots_are_located(campaigns):
    """Each pivot is the centre of its lengths' spheres (with P1's seated contacts): their
    distance apart, blind to the rigid motion the readings cannot see, is the true one."""
    from doe_calib.estimation.identify import identify
    from doe_calib.estimation.sockets import located_sockets
    from doe_calib.model.marker_model import build_model

    d, _ = campaigns
    robot, tool = _robot_tool(d)
    meas = read_measurements(d / "ballbar.csv", robot, tool)
    model = build_model(robot, tool, "joint_offset+geometry")
    with pytest.warns(Warning):  # the selection leaves at nominal what the arcs barely see
        result = identify(model, meas)
    found = located_sockets(model, meas, result.parameters, result.covariance)
    (p1, std1), (p2, std2) = found["P1"], found["P2"]
    apart = np.linalg.norm(p1 - p2) - np.linalg.norm(np.subtract(*PIVOTS_M.values()))
    print(f"pivots apart: {apart * 1e3:+.4f} mm off; std {std1 * 1e3}, {std2 * 1e3} mm")
    assert abs(apart) < 5e-6 and np.all(std1 < 5e-6) and np.all(std2 < 5e-6)
    assert any(n.startswith("48 socket contacts") or "ballbar lengths in 2 sockets" in n
               for n in result.warnings)


def test_touches_on_a_line_are_refused(ur10, truth, campaigns, tmp_path):
    from doe_calib.estimation.identify import identify
    from doe_calib.model.marker_model import build_model

    d, _ = campaigns
    rng = np.random.default_rng(4)
    rows = []
    for a in np.linspace(-0.3, 0.3, 6):
        q = None
        while q is None:
            q = _reach(ur10, truth, np.array([0.3 + a, 0.2, 0.05]), rng)
        rows.append(_row(f"l{len(rows)}", q, plane="edge"))
    with open(d / "touches.csv") as f:
        _write(tmp_path / "line.csv", list(csv.DictReader(f)) + rows)
    robot, tool = _robot_tool(d)
    meas = read_measurements(tmp_path / "line.csv", robot, tool, sigma=TOUCH_MM * 1e-3)
    with pytest.raises(DataError, match=r"line.csv: plane 'edge': its 6 touches \(lines 62, 63, "
                                        r"64, 65, 66, 67\) lie on a line"):
        identify(build_model(robot, tool, "joint_offset+geometry"), meas)
