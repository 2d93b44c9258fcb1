"""Ball-in-socket contacts (formats.md §3, *Socket contacts*) through ``identify`` and
``predict``, judged on a campaign simulated independently of our model (issue #31).

A UR10 with placement errors up to 0.5 mm / 0.05° on every joint, joint offsets up to
0.1°, the ball centre 1 mm off nominal; three sockets on the table, 15 contacts each
seated by IK on the true robot (seating scatter 0.01 mm per axis); only the controller's
joint values are written. The base pose cannot be seen: the prediction is compared to
the truth after a rigid registration.
"""
import csv

import independent_sim as sim
import numpy as np
import pinocchio as pin
import pytest

from doe_calib import Robot, Tool
from doe_calib.cli import main
from doe_calib.errors import DataError
from doe_calib.io.csv_files import read_measurements

BALL_M = np.array([0.0, 0.0, 0.10])  # nominal ball centre, flange frame
SOCKETS_M = {"S1": [0.65, 0.25, 0.05], "S2": [0.45, -0.55, 0.05], "S3": [-0.25, 0.70, 0.05]}
SEATING_MM = 0.01


@pytest.fixture(scope="module")
def truth(ur10):
    return true_robot(ur10)


def true_robot(ur10):
    """The campaign's true UR10 (placement errors, offsets, the ball 1 mm off nominal)."""
    return sim.ball_on_stem_truth(ur10)


def _ball(ur10, truth, q):
    """True ball centre (3,), m, at commanded q (N,) (the robot's root frame)."""
    return sim.marker_positions(ur10, truth, q[None], np.zeros((1, 6)))[0, 0]


def _seat(ur10, truth, target, rng):
    """Commanded q that puts the true ball centre on ``target``, by damped Gauss–Newton on
    position from a random start (a varied tool orientation), or None."""
    q = sim.random_configurations(ur10, 1, rng, within=np.c_[-np.pi * np.ones(6),
                                                            np.pi * np.ones(6)])[0]
    for _ in range(60):
        e = target - _ball(ur10, truth, q)
        if np.linalg.norm(e) < 1e-12:
            return (q + np.pi) % (2 * np.pi) - np.pi  # inside every joint's limits
        jac = np.array([(_ball(ur10, truth, q + h) - _ball(ur10, truth, q - h)) / 2e-7
                        for h in np.eye(6) * 1e-7]).T
        q = q + jac.T @ np.linalg.solve(jac @ jac.T + 1e-6 * np.eye(3), e)
    return None


def _q_columns(q):
    return {f"q{k + 1}": repr(float(v)) for k, v in enumerate(np.degrees(q))}


@pytest.fixture(scope="module")
def campaign(ur10, truth, tmp_path_factory):
    """The contacts file (every socket unknown), the tool, 40 new configurations (a file
    and their q) and each contact's (socket, q)."""
    rng = np.random.default_rng(7)
    d = tmp_path_factory.mktemp("sockets")
    seats = []
    for name, point in SOCKETS_M.items():
        seated = 0
        while seated < 15:
            target = np.asarray(point) + rng.normal(scale=SEATING_MM * 1e-3, size=3)
            q = _seat(ur10, truth, target, rng)
            if q is None:
                continue
            seated += 1
            seats.append((name, q))
    _write_contacts(d / "contacts.csv", seats)
    (d / "tool.yaml").write_text("flange: tool0\nmarkers:\n  ball: [0.0, 0.0, 100.0]\n")
    q_new = sim.random_configurations(ur10, 40, rng, within=np.c_[-np.pi * np.ones(6),
                                                                  np.pi * np.ones(6)])
    with open(d / "new.csv", "w", newline="") as f:
        writer = csv.DictWriter(f, fieldnames=["pose", *_q_columns(q_new[0]), "marker"])
        writer.writeheader()
        writer.writerows({"pose": str(i), **_q_columns(q), "marker": "ball"}
                         for i, q in enumerate(q_new))
    return d, q_new, seats


def _write_contacts(path, seats, given=None, drawn_mm=None):
    """A contacts file of ``seats`` ((socket, q) each); ``given``: socket → its position,
    mm, written on its rows (else x, y, z empty); ``drawn_mm``: the std of each given
    position (its drawing's tolerance), mm."""
    given, count = given or {}, {}
    rows = []
    for name, q in seats:
        count[name] = count.get(name, 0) + 1
        xyz = given.get(name, ("", "", ""))
        rows.append({"pose": f"{name}-{count[name]}", **_q_columns(q), "marker": "ball",
                     "socket": name, **{c: str(v) for c, v in zip("xyz", xyz)},
                     **({"socket_sigma": str(drawn_mm) if name in given else ""}
                        if drawn_mm else {})})
    with open(path, "w", newline="") as f:
        writer = csv.DictWriter(f, fieldnames=list(rows[0]))
        writer.writeheader()
        writer.writerows(rows)


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


def test_contacts_are_read_as_sockets(ur10, campaign):
    d, _, _ = campaign
    robot = Robot.from_urdf(sim.ur10_urdf(), flange="tool0")
    meas = read_measurements(d / "contacts.csv", robot, Tool.from_yaml(d / "tool.yaml"),
                             sigma=1e-5)
    assert meas.socket_names == ("S1", "S2", "S3")
    assert meas.contact.all() and np.bincount(meas.socket).tolist() == [15, 15, 15]
    assert meas.n_coordinates == 3 * 45 - 9  # each socket's point is 3 unknowns


@pytest.mark.parametrize("change, said", [
    ((1, "1.0", "2.0", "3.0"), r"socket 'S1' at \(1, 2, 3\) mm here but no x, y, z on line 2"),
    ((0, "1.0", "", ""), "socket 'S1' with some of x, y, z: give all three"),
])
def test_a_socket_gives_one_position_or_none(campaign, tmp_path, change, said):
    d, _, _ = campaign
    lines = (d / "contacts.csv").read_text().splitlines()
    row, *xyz = change
    lines[row + 2] = lines[row + 2].rstrip(",") + "," + ",".join(xyz)
    bad = tmp_path / "bad.csv"
    bad.write_text("\n".join(lines) + "\n")
    robot = Robot.from_urdf(sim.ur10_urdf(), flange="tool0")
    with pytest.raises(DataError, match=f"line {row + 3}, column 'x'.*{said}"):
        read_measurements(bad, robot, Tool.from_yaml(d / "tool.yaml"), sigma=1e-5)


def test_socket_campaign_predicts_new_configurations(ur10, truth, campaign, capsys):
    d, q_new, _ = campaign
    urdf = str(sim.ur10_urdf())
    assert main(["identify", "--robot", urdf, "--tool", str(d / "tool.yaml"),
                 "--data", str(d / "contacts.csv"), "--sigma", str(SEATING_MM),
                 "--model", "joint_offset+geometry", "--out", str(d / "r.json")]) == 0
    said = capsys.readouterr()
    assert "socket contacts cannot see the robot's base pose" in said.out + said.err
    assert said.out.count("45 socket contacts in 3 sockets") == 1  # the kept fit's, once
    assert "readings               = 45" in said.out  # each socket's point costs 3
    assert "observations (3K − 3S) = 126 (S = 3 sockets of unknown position)" in said.out
    assert main(["predict", "--result", str(d / "r.json"), "--data", str(d / "new.csv"),
                 "--out", str(d / "pred.csv")]) == 0
    with open(d / "pred.csv") as f:
        pred = np.array([[float(r[c]) for c in "xyz"] for r in
                         csv.DictReader(line for line in f if not line.startswith("#"))]) / 1e3
    true = sim.marker_positions(ur10, truth, q_new, np.zeros((40, 6)))[:, 0]
    nominal = sim.Truth.nominal(ur10, BALL_M[None])
    before = _registered_rms_mm(sim.marker_positions(ur10, nominal, q_new,
                                                     np.zeros((40, 6)))[:, 0], true)
    after = _registered_rms_mm(pred, true)
    similar = _registered_rms_mm(pred, true, scale=True)
    print(f"nominal {before:.3f} mm; identified {after:.4f} mm (rigid), {similar:.4f} mm "
          f"(similarity)")
    assert before > 1.0
    assert similar <= 0.03  # what contacts can see: all but a rigid motion and the scale
    # the scale rides on the one link length held at the URDF's (0.08 mm off here, 1.3e-4)
    assert after <= 0.15


def test_contacts_mix_with_tracker_readings(ur10, truth, campaign, tmp_path):
    """Tracker readings of the ball (base 2 m away, turned) and the contacts in one file: the
    base is fitted from the tracker rows, the sockets land where they are in the tracker
    frame, and new configurations are predicted there with no registration."""
    from dataclasses import replace

    from doe_calib.estimation.identify import FitSettings, identify
    from doe_calib.estimation.sockets import located_sockets
    from doe_calib.model.marker_model import build_model

    d, q_new, _ = campaign
    rot = pin.exp3(np.array([0.3, -0.2, 1.9]))
    placed = replace(truth, base_rotvec=pin.log3(rot), base_position=np.array([2.0, -0.5, 0.3]))
    rng = np.random.default_rng(3)
    q = sim.random_configurations(ur10, 20, rng, within=np.c_[-np.pi * np.ones(6),
                                                              np.pi * np.ones(6)])
    x = sim.marker_positions(ur10, placed, q, np.zeros((20, 6)))[:, 0]
    x = (x + rng.normal(scale=SEATING_MM * 1e-3, size=x.shape)) * 1e3
    lines = (d / "contacts.csv").read_text().splitlines()
    lines += [",".join([f"t{i}", *_q_columns(qi).values(), "ball", "",
                        *(repr(float(v)) for v in xi)])
              for i, (qi, xi) in enumerate(zip(q, x))]
    (tmp_path / "mixed.csv").write_text("\n".join(lines) + "\n")
    robot = Robot.from_urdf(sim.ur10_urdf(), flange="tool0")
    tool = Tool.from_yaml(d / "tool.yaml")
    meas = read_measurements(tmp_path / "mixed.csv", robot, tool, sigma=SEATING_MM * 1e-3)
    assert meas.contact.sum() == 45 and (~meas.contact).sum() == 20
    model = build_model(robot, tool, "joint_offset+geometry")
    result = identify(model, meas, settings=FitSettings(select="none"))
    assert not any("socket contacts cannot see" in n for n in result.warnings)
    found = located_sockets(model, meas, result.parameters, result.covariance)
    for name, point in SOCKETS_M.items():  # the tracker frame: base ∘ root-frame point
        where, std = found[name]
        error = where - (rot @ point + placed.base_position)
        assert np.linalg.norm(error) < 5e-5 and np.all(np.abs(error) < 4 * std)
        assert np.all(std < 2e-5)
    from doe_calib.io.measurements import Configurations

    predicted = result.predict(Configurations.from_arrays(q_new), model).xyz
    true = sim.marker_positions(ur10, placed, q_new, np.zeros((40, 6)))[:, 0]
    rms = np.sqrt(np.mean(np.sum((predicted - true) ** 2, axis=1))) * 1e3
    print(f"mixed file: {rms:.4f} mm at new configurations, tracker frame, no registration")
    assert rms < 0.03


#: The socket plate: its frame from the robot's root (rotation vector, rad; origin, m), and
#: the drawing's (or CMM's) tolerance of each socket's position per axis, mm.
PLATE = (np.array([0.02, -0.01, 0.6]), np.array([-0.3, 0.2, -0.05]))
DRAWING_MM = 0.005


def _in_plate(points):
    """Points (…, 3), m, from the robot's root frame to the plate's."""
    return points @ pin.exp3(PLATE[0]).T + PLATE[1]


@pytest.fixture(scope="module")
def drawing():
    """Each socket's position as the plate's drawing gives it, mm (plate frame): the true
    one off by the drawing's tolerance."""
    rng = np.random.default_rng(17)
    return {name: _in_plate(np.asarray(p)) * 1e3 + rng.normal(scale=DRAWING_MM, size=3)
            for name, p in SOCKETS_M.items()}


def _identify_and_predict(d, name, seats, given, capsys):
    """Identify from the contacts with the ``given`` positions, predict the new
    configurations: (predicted (40, 3), m, plate frame; identify's words)."""
    _write_contacts(d / f"{name}.csv", seats, given, DRAWING_MM)
    assert main(["identify", "--robot", str(sim.ur10_urdf()), "--tool", str(d / "tool.yaml"),
                 "--data", str(d / f"{name}.csv"), "--sigma", str(SEATING_MM),
                 "--model", "joint_offset+geometry",
                 "--out", str(d / f"{name}.json")]) == 0
    said = capsys.readouterr()
    assert main(["predict", "--result", str(d / f"{name}.json"), "--data", str(d / "new.csv"),
                 "--out", str(d / f"{name}_pred.csv")]) == 0
    with open(d / f"{name}_pred.csv") as f:
        pred = np.array([[float(r[c]) for c in "xyz"] for r in
                         csv.DictReader(line for line in f if not line.startswith("#"))]) / 1e3
    return pred, said.out + said.err


def test_sockets_of_given_position_see_base_and_scale(ur10, truth, campaign, drawing, capsys):
    """Issue #31's done-when: the ball-in-socket campaign with the plate's drawing giving the
    sockets' positions is predicted to ≤ 0.03 mm at new configurations, in the plate frame."""
    d, q_new, seats = campaign
    pred, said = _identify_and_predict(d, "given3", seats, drawing, capsys)
    assert "readings               = 45" in said and "observations (3K)      = 135" in said
    assert "socket contacts" not in said.split("fixed")[0]  # nothing unseen but the flange
    assert "without a known length" not in said and "base's turn" not in said
    true = sim.marker_positions(ur10, truth, q_new, np.zeros((40, 6)))[:, 0]
    plate = np.sqrt(np.mean(np.sum((pred - _in_plate(true)) ** 2, axis=1))) * 1e3
    rigid = _registered_rms_mm(pred, true)
    print(f"three given sockets: {plate:.4f} mm in the plate frame, {rigid:.4f} mm after a "
          f"rigid registration")
    assert rigid <= 0.03 and plate <= 0.05


def test_one_known_length(ur10, truth, campaign, drawing, capsys):
    """Two sockets given (a known length), one unknown: the scale is seen, the turn about
    the two sockets' line is not, and is said."""
    d, q_new, seats = campaign
    given = {k: drawing[k] for k in ("S1", "S2")}
    pred, said = _identify_and_predict(d, "given2", seats, given, capsys)
    assert "cannot see the base's turn about that line" in said
    assert "without a known length" not in said
    true = sim.marker_positions(ur10, truth, q_new, np.zeros((40, 6)))[:, 0]
    rigid, similar = _registered_rms_mm(pred, true), _registered_rms_mm(pred, true, scale=True)
    print(f"two given sockets, one unknown: {rigid:.4f} mm after a rigid registration, "
          f"{similar:.4f} mm with a scale")
    assert rigid <= 0.03


def test_socket_column_written_back(campaign, drawing, tmp_path, capsys):
    """A file of given and unknown sockets reads back the same after writing it, and
    ``predict`` of contacts keeps each row's socket beside its predicted x, y, z."""
    from doe_calib.io.csv_files import write_measurements

    d, _, seats = campaign
    _write_contacts(tmp_path / "mixed.csv", seats, {"S2": drawing["S2"]})
    robot = Robot.from_urdf(sim.ur10_urdf(), flange="tool0")
    tool = Tool.from_yaml(d / "tool.yaml")
    meas = read_measurements(tmp_path / "mixed.csv", robot, tool, sigma=1e-5)
    assert meas.contact.sum() == 30 and len(meas.sockets_used) == 2  # S2 is a read point
    write_measurements(tmp_path / "again.csv", meas, robot, tool)
    again = read_measurements(tmp_path / "again.csv", robot, tool, sigma=1e-5)
    assert again.socket_names == meas.socket_names
    assert np.array_equal(again.socket, meas.socket)
    assert np.array_equal(np.isnan(again.xyz), np.isnan(meas.xyz))
    assert np.allclose(again.xyz[~again.contact], meas.xyz[~meas.contact])
    assert main(["identify", "--robot", str(sim.ur10_urdf()), "--tool", str(d / "tool.yaml"),
                 "--data", str(tmp_path / "mixed.csv"), "--sigma", str(SEATING_MM),
                 "--model", "joint_offset+geometry", "--out", str(tmp_path / "r.json")]) == 0
    said = capsys.readouterr()
    assert "one socket of given position cannot see the base's turn" in said.out + said.err
    assert "cannot see the robot's scale without a known length" in said.out
    assert main(["predict", "--result", str(tmp_path / "r.json"), "--data",
                 str(tmp_path / "mixed.csv"), "--out", str(tmp_path / "pred.csv")]) == 0
    said = capsys.readouterr().out
    assert "a turn of every point about that socket is not seen" in said
    with open(tmp_path / "pred.csv") as f:
        rows = list(csv.DictReader(line for line in f if not line.startswith("#")))
    assert [r["socket"] for r in rows] == [name for name, _ in seats]
    assert all(r["x"] for r in rows)


def test_compensate_says_what_contacts_cannot_see(campaign, capsys):
    """``compensate`` after a fit to unknown sockets: its predicted std is relative to the
    sockets' frame, the scale stated per metre beside it, not ~1 mm of unseen parameters."""
    d, q_new, _ = campaign
    assert main(["identify", "--robot", str(sim.ur10_urdf()), "--tool", str(d / "tool.yaml"),
                 "--data", str(d / "contacts.csv"), "--sigma", str(SEATING_MM),
                 "--model", "joint_offset+geometry", "--out", str(d / "c.json")]) == 0
    with open(d / "targets.csv", "w", newline="") as f:
        writer = csv.DictWriter(f, fieldnames=["pose", *_q_columns(q_new[0])])
        writer.writeheader()
        writer.writerows({"pose": str(i), **_q_columns(q)} for i, q in enumerate(q_new[:5]))
    capsys.readouterr()
    assert main(["compensate", "--result", str(d / "c.json"), "--targets",
                 str(d / "targets.csv"), "--tcp", "ball", "--position-only",
                 "--out", str(d / "compensated.csv")]) == 0
    said = capsys.readouterr().out
    assert "predicted_std is relative to the sockets' frame" in said
    assert "the scale is not seen (no known length): ±1.63 mm per metre" in said
    with open(d / "compensated.csv") as f:
        rows = list(csv.DictReader(line for line in f if not line.startswith("#")))
    assert max(float(r["predicted_std_mm"]) for r in rows) < 0.05  # before: 1.5–2.5 mm


@pytest.mark.parametrize("cell, said", [
    ("-0.005", "socket_sigma -0.005 mm: a position's std is 0 or more"),
    ("0.007", r"socket 'S1' with socket_sigma 0.007 mm here but 0.005 mm on line 2"),
])
def test_socket_sigma_is_one_per_given_socket(campaign, drawing, tmp_path, cell, said):
    d, _, seats = campaign
    _write_contacts(tmp_path / "given.csv", seats, {"S1": drawing["S1"]}, DRAWING_MM)
    lines = (tmp_path / "given.csv").read_text().splitlines()
    lines[3] = lines[3].rsplit(",", 1)[0] + "," + cell
    (tmp_path / "given.csv").write_text("\n".join(lines) + "\n")
    robot = Robot.from_urdf(sim.ur10_urdf(), flange="tool0")
    with pytest.raises(DataError, match=f"line 4, column 'socket_sigma'.*{said}"):
        read_measurements(tmp_path / "given.csv", robot, Tool.from_yaml(d / "tool.yaml"),
                          sigma=1e-5)


def test_given_socket_residuals_are_whitened(ur10, campaign, drawing, tmp_path):
    """A given socket's std makes its contacts' errors correlated (σ²I + σ_s²11ᵀ per axis):
    the weighted residuals' ‖r‖² is that correlated χ², for any parameters, and their
    Jacobian that of finite differences."""
    from doe_calib.estimation.weighted_residuals import (
        marker_points,
        residual_norm2,
        weighted_residual,
    )
    from doe_calib.model.marker_model import build_model

    d, _, seats = campaign
    _write_contacts(tmp_path / "given.csv", seats, drawing, DRAWING_MM)
    robot = Robot.from_urdf(sim.ur10_urdf(), flange="tool0")
    tool = Tool.from_yaml(d / "tool.yaml")
    meas = read_measurements(tmp_path / "given.csv", robot, tool, sigma=SEATING_MM * 1e-3)
    model = build_model(robot, tool, "joint_offset+geometry")
    values = model.nominal().values + np.random.default_rng(2).normal(
        scale=1e-4, size=len(model.nominal().values))
    e = meas.xyz - marker_points(model, meas, values)
    chi2 = 0.0
    for k in range(len(meas.socket_names)):
        at = meas.socket == k
        cov = (SEATING_MM * 1e-3) ** 2 * np.eye(at.sum()) + (DRAWING_MM * 1e-3) ** 2
        chi2 += float(np.sum(e[at] * np.linalg.solve(cov, e[at])))
    assert residual_norm2(model, meas, values) == pytest.approx(chi2, rel=1e-9)
    r, jac = weighted_residual(model, meas, values)
    for i in (7, 20):
        step = np.eye(len(values))[i] * 1e-7
        fd = (weighted_residual(model, meas, values + step, jacobian=False)[0] -
              weighted_residual(model, meas, values - step, jacobian=False)[0]) / 2e-7
        assert np.allclose(jac[:, i], fd, rtol=1e-5, atol=1e-6 * np.abs(fd).max())
