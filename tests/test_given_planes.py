"""Plane touches on planes of given position (formats.md §3, *Plane touches*; issue #31):
x, y, z a point of the plane and nx, ny, nz its normal on every touch, judged on a campaign
simulated independently of our model.

The truth is the UR10 of tests/test_plane_and_ballbar.py (placement errors up to 0.5 mm /
0.05° on every joint, offsets up to 0.1°, the ball centre 1 mm off nominal), its base placed
in the planes' frame 1.8 mm and 0.1° off the URDF's root. Three faces known from a drawing:
a table top and two faces of a block (one upright, one slanted), 20 touches each, scatter
0.01 mm along the normal; only the controller's joint values are written.
"""
import csv

import independent_sim as sim
import numpy as np
import pytest
from seated_contacts import q_columns, seat

from doe_calib import Robot, Tool, build_model
from doe_calib.cli import main
from doe_calib.errors import DataError
from doe_calib.estimation.preparation import PLANES_SCALE, PLANES_SHIFT, PLANES_TURN, prepare
from doe_calib.io.csv_files import read_measurements

BALL_M = np.array([0.0, 0.0, 0.10])
TOUCH_MM = 0.01
#: Each plane: a point on it, two in-plane axes, half-extent along them (m).
PLANES = {"table": ([0.3, 0.0, 0.05], [1, 0, 0], [0, 1, 0], 0.45),
          "front": ([0.75, 0.0, 0.35], [0, 1, 0], [0, 0, 1], 0.2),
          "slant": ([0.1, -0.7, 0.35], [1, 0, 0], [0, 1 / np.sqrt(2), 1 / np.sqrt(2)], 0.2)}


@pytest.fixture(scope="module")
def truth(ur10):
    rng = np.random.default_rng(31)  # the truth of tests/test_socket_contacts.py
    n = len(ur10.joints)
    twists = rng.uniform(-1, 1, (n, 6)) * np.r_[[0.5e-3] * 3, [np.radians(0.05)] * 3]
    offsets = rng.uniform(-1, 1, n) * np.radians(0.1)
    off = rng.normal(size=3)
    ball = BALL_M + 1e-3 * off / np.linalg.norm(off)
    turn = np.radians(0.1) * np.array([0.6, -0.8, 0.0])
    return sim.Truth(turn, np.array([1.2e-3, -0.8e-3, 1.1e-3]), ball[None], offsets, twists)


def _write(path, rows):
    names = list(dict.fromkeys(k for r in rows for k in r))
    with open(path, "w", newline="") as f:
        writer = csv.DictWriter(f, fieldnames=names, restval="")
        writer.writeheader()
        writer.writerows(rows)


def _plane_cells(point, normal) -> dict:
    """x, y, z (mm) and nx, ny, nz of a plane as its drawing gives it (the normal not unit)."""
    return {**{c: repr(float(v) * 1000.0) for c, v in zip("xyz", point)},
            **{c: repr(float(v) * 2.0) for c, v in zip(("nx", "ny", "nz"), normal)}}


@pytest.fixture(scope="module")
def campaign(ur10, truth, tmp_path_factory):
    """(folder, the touches' rows, the new configurations (40, 6), rad)."""
    rng = np.random.default_rng(5)
    d = tmp_path_factory.mktemp("given_planes")
    rows = []
    for name, (point, e1, e2, half) in PLANES.items():
        e1, e2 = np.asarray(e1, float), np.asarray(e2, float)
        normal = np.cross(e1, e2)
        touched = 0
        while touched < 20:
            a, b = rng.uniform(-half, half, 2)
            target = np.asarray(point) + a * e1 + b * e2 + \
                normal * rng.normal(scale=TOUCH_MM * 1e-3)
            q = seat(ur10, truth, target, rng)
            if q is not None:
                touched += 1
                rows.append({"pose": f"{name}-{touched}", **q_columns(q), "marker": "ball",
                             "plane": name, **_plane_cells(point, normal)})
    _write(d / "given.csv", rows)
    (d / "tool.yaml").write_text("flange: tool0\nmarkers:\n  ball: [0.0, 0.0, 100.0]\n")
    q_new = rng.uniform(-np.pi, np.pi, (40, 6))
    _write(d / "new.csv", [{"pose": str(i), **q_columns(q), "marker": "ball"}
                           for i, q in enumerate(q_new)])
    return d, rows, q_new


def _robot_tool(d):
    return Robot.from_urdf(sim.ur10_urdf(), flange="tool0"), Tool.from_yaml(d / "tool.yaml")


def _identify_and_predict(d, data, capsys):
    out = d / f"{data}.json"
    assert main(["identify", "--robot", str(sim.ur10_urdf()), "--tool", str(d / "tool.yaml"),
                 "--data", str(d / f"{data}.csv"), "--sigma", str(TOUCH_MM),
                 "--model", "joint_offset+geometry", "--out", str(out)]) == 0
    said = capsys.readouterr()
    assert main(["predict", "--result", str(out), "--data", str(d / "new.csv"),
                 "--out", str(d / f"{data}-pred.csv")]) == 0
    with open(d / f"{data}-pred.csv") as f:
        pred = np.array([[float(r[c]) for c in "xyz"] for r in
                         csv.DictReader(line for line in f if not line.startswith("#"))])
    return said.out + said.err, pred / 1e3


def _rms_mm(predicted, true) -> float:
    """3-D RMS (mm) of ``predicted`` − ``true`` (K, 3), m, in the planes' frame: no
    registration."""
    return float(np.sqrt(np.mean(np.sum((predicted - true) ** 2, axis=1))) * 1e3)


def test_given_planes_are_read(campaign):
    d, _, _ = campaign
    robot, tool = _robot_tool(d)
    m = read_measurements(d / "given.csv", robot, tool, sigma=1e-5)
    assert m.touch.all() and m.given_plane.all() and m.contact.all()
    assert len(m.planes_used) == 0
    assert m.n_coordinates == 60  # one per touch; a given plane costs nothing
    assert np.allclose(np.linalg.norm(m.plane_normal, axis=1), 1.0)  # normalised
    table = m.plane == m.plane_names.index("table")
    assert np.allclose(m.plane_normal[table], [0, 0, 1]) and np.allclose(m.xyz[table, 2], 0.05)


def test_given_planes_predict_in_their_frame(ur10, truth, campaign, capsys):
    d, _, q_new = campaign
    said, pred = _identify_and_predict(d, "given", capsys)
    assert "cannot see the robot's base pose" not in said
    assert "cannot see the base's shift" not in said and "turn about their normal" not in said
    assert PLANES_SCALE.split("(")[0] in said  # three planes meet at one point
    true = sim.marker_positions(ur10, truth, q_new, np.zeros((40, 6)))[:, 0]
    nominal = sim.Truth.nominal(ur10, BALL_M[None])
    before = _rms_mm(sim.marker_positions(ur10, nominal, q_new, np.zeros((40, 6)))[:, 0], true)
    after = _rms_mm(pred, true)
    corner = np.linalg.solve([np.cross(e1, e2) for _, e1, e2, _ in PLANES.values()],
                             [np.cross(e1, e2) @ p for p, e1, e2, _ in PLANES.values()])
    grow = np.sum((pred - corner) * (true - corner)) / np.sum((pred - corner) ** 2)
    scaled = _rms_mm(corner + grow * (pred - corner), true)
    print(f"given planes: nominal {before:.3f} mm; identified {after:.4f} mm, in the planes' "
          f"frame, no registration; {scaled:.4f} mm grown about the planes' corner by "
          f"{(grow - 1) * 1e6:.0f} ppm")
    assert before > 1.0
    assert after <= 0.25  # the scale about the corner rides on the link length held
    assert scaled <= 0.05  # all the rest is seen, the base too


def _edited(d, rows, tmp_path, edit):
    rows = [dict(r) for r in rows]
    edit(rows)
    _write(tmp_path / "bad.csv", rows)
    return tmp_path / "bad.csv"


def test_a_plane_given_differently_is_refused(campaign, tmp_path):
    d, rows, _ = campaign
    robot, tool = _robot_tool(d)

    def tilt(rows):
        rows[4]["nz"] = "1.9"

    with pytest.raises(DataError) as e:
        read_measurements(_edited(d, rows, tmp_path, tilt), robot, tool, sigma=1e-5)
    assert e.value.line == 6 and e.value.column == f"'nz' ({list(rows[0]).index('nz') + 1})"
    assert "plane 'table' with nz 1.9 here but 2 on line 2" in str(e.value)

    def half(rows):
        rows[7]["ny"] = ""

    with pytest.raises(DataError) as e:
        read_measurements(_edited(d, rows, tmp_path, half), robot, tool, sigma=1e-5)
    assert e.value.line == 9 and e.value.column == f"'ny' ({list(rows[0]).index('ny') + 1})"
    assert "give all six" in str(e.value)


def test_given_and_unknown_planes_mix(ur10, truth, campaign, tmp_path, capsys):
    d, rows, q_new = campaign

    def forget(rows):
        for r in rows:
            if r["plane"] == "slant":
                r.update({c: "" for c in ("x", "y", "z", "nx", "ny", "nz")})

    path = _edited(d, rows, d, forget)
    path.rename(d / "mixed.csv")
    robot, tool = _robot_tool(d)
    m = read_measurements(d / "mixed.csv", robot, tool, sigma=1e-5)
    assert m.given_plane.sum() == 40 and len(m.planes_used) == 1
    assert m.n_coordinates == 60 - 3
    said, pred = _identify_and_predict(d, "mixed", capsys)
    assert "cannot see the base's shift parallel to every one of them" in said  # x along both
    true = sim.marker_positions(ur10, truth, q_new, np.zeros((40, 6)))[:, 0]
    along = np.mean(pred - true, axis=0)[1]  # the base's shift along y, parallel to both
    shifted = _rms_mm(pred - [0.0, along, 0.0], true)
    print(f"table and front given, slant unknown: {_rms_mm(pred, true):.4f} mm; "
          f"{shifted:.4f} mm less the mean shift along y ({along * 1e3:.3f} mm; the truth's "
          f"base is {truth.base_position[1] * 1e3:.3f} mm)")
    assert shifted <= 0.25


def test_one_given_plane_leaves_the_shift_and_turn(campaign):
    d, _, _ = campaign
    robot, tool = _robot_tool(d)
    m = read_measurements(d / "given.csv", robot, tool, sigma=1e-5)
    m = m.subset(m.plane == m.plane_names.index("table"))
    model = build_model(robot, tool, "joint_offset+geometry")
    with pytest.warns(Warning):
        params = prepare(model, m)[0]
    reasons = [why for why, free in zip(params.fixed_reason, params.free) if not free]
    assert sum(why.startswith(PLANES_SHIFT.split("{")[0]) for why in reasons) == 2
    assert sum(why.startswith(PLANES_TURN.split("{")[0]) for why in reasons) == 1


def test_jacobian_matches_finite_differences(campaign):
    """A given plane's residual is the model point's signed distance to it: its Jacobian is
    exact, against central differences, at the nominal model."""
    from doe_calib.estimation.weighted_residuals import weighted_residual

    d, _, _ = campaign
    robot, tool = _robot_tool(d)
    meas = read_measurements(d / "given.csv", robot, tool, sigma=TOUCH_MM * 1e-3)
    model = build_model(robot, tool, "joint_offset+geometry")
    nominal, h = model.nominal().values, 1e-7
    r, jac = weighted_residual(model, meas, nominal)
    numeric = np.array([(weighted_residual(model, meas, nominal + e, False)[0] -
                         weighted_residual(model, meas, nominal - e, False)[0]) / (2 * h)
                        for e in np.eye(len(nominal)) * h]).T
    assert np.abs(numeric - jac).max() <= 1e-5 * np.abs(jac).max()
    along = np.sum(r.reshape(-1, 3) * meas.plane_normal, axis=1, keepdims=True)
    assert np.allclose(r.reshape(-1, 3), meas.plane_normal * along)  # ρ·n, 3 rows a touch


def test_given_planes_write_back_as_read(campaign, tmp_path):
    from doe_calib.io.csv_files import write_measurements

    d, _, _ = campaign
    robot, tool = _robot_tool(d)
    meas = read_measurements(d / "given.csv", robot, tool)
    write_measurements(tmp_path / "back.csv", meas, robot, tool)
    back = read_measurements(tmp_path / "back.csv", robot, tool)
    assert np.array_equal(back.plane, meas.plane) and back.plane_names == meas.plane_names
    assert np.allclose(back.xyz, meas.xyz, rtol=0, atol=1e-12)
    assert np.allclose(back.plane_normal, meas.plane_normal, rtol=0, atol=1e-15)
