"""``doe-calib iso9283 design`` and ``report``: the test's geometry and inverse kinematics,
its export, and the report of simulated cycles against a hand computation."""
import csv
import json
import math
from pathlib import Path

import numpy as np
import pytest
from scipy.spatial.transform import Rotation
from test_iso9283 import hand_ap_rp

from doe_calib import examples
from doe_calib.cli import main
from doe_calib.estimation.predict import result_model
from doe_calib.estimation.result import IdentificationResult
from doe_calib.io.measurements import Configurations
from doe_calib.iso9283.predicted import predicted_accuracy
from doe_calib.model.robot import Robot
from doe_calib.model.tool import Tool

ROBOT = ["--robot", examples.ROBOT_URDF, "--tool", examples.TOOL_YAML]
POSES = ["P1", "P2", "P3", "P4", "P5"]
CYCLES = 6


@pytest.fixture(scope="module")
def files(tmp_path_factory):
    return tmp_path_factory.mktemp("iso")


@pytest.fixture(scope="module")
def design(files):
    out = files / "iso.json"
    assert main(["iso9283", "design", *ROBOT, "--tcp", "A", "--load", "250@0,0,200",
                 "--cycles", str(CYCLES), "--out", str(out)]) == 0
    return out


@pytest.fixture(scope="module")
def result(files):
    """An identification (joint offsets) of a simulated campaign, and its true parameters."""
    common = [*ROBOT, "--model", "joint_offset"]
    assert main(["simulate", *common, "--poses", "12", "--sigma", "0.01", "--seed", "2",
                 "--no-collision", "--out", str(files / "calib.csv"), "--truth-out",
                 str(files / "truth.json")]) == 0
    assert main(["identify", *common, "--data", str(files / "calib.csv"), "--sigma", "0.01",
                 "--out", str(files / "result.json")]) == 0
    return files / "result.json"


@pytest.fixture(scope="module")
def identified_design(files, result):
    out = files / "iso_identified.json"
    assert main(["iso9283", "design", *ROBOT, "--tcp", "A", "--load", "250@0,0,200",
                 "--cycles", str(CYCLES), "--result", str(result), "--out", str(out)]) == 0
    return out


def _cycles(files, design, name, seed):
    out = files / f"{name}.csv"
    assert main(["simulate", *ROBOT, "--model", "joint_offset", "--design", str(design),
                 "--truth", str(files / "truth.json"), "--sigma", "0.01", "--seed", str(seed),
                 "--no-collision", "--out", str(out)]) == 0
    return out


def test_design_poses_are_the_standards_cube_reached_by_ik(design):
    data = json.loads(design.read_text())
    assert data["format"] == "doe_calib.design"
    block = data["iso9283"]
    centre, edge = np.array(block["cube"]["centre_mm"]), block["cube"]["edge_mm"]
    assert edge > 100.0 and block["tcp"] == "A" and block["load"] == "250@0,0,200"
    # ISO 9283 §6: P1 the centre; P2…P5 on the diagonal plane C1-C2-C7-C8, 10 % of its
    # diagonal (edge·√3) from the corners
    corners = {"P2": (-1, -1, -1), "P3": (1, -1, -1), "P4": (1, 1, 1), "P5": (-1, 1, 1)}
    targets = {p: np.array(v) for p, v in block["targets_mm"].items()}
    assert np.allclose(targets["P1"], centre, atol=1e-9)
    for pose, signs in corners.items():
        corner = [c + s * edge / 2 for c, s in zip(centre, signs)]
        assert abs(math.dist(targets[pose], corner) - 0.1 * edge * math.sqrt(3)) < 1e-9
    ids = [p["pose"] for p in data["poses"]]
    assert ids == [f"{p}-{c:02d}" for c in range(1, CYCLES + 1) for p in POSES]
    # each visit's joint values put marker A on its target (Pinocchio's forward kinematics)
    robot, tool = Robot.from_urdf(examples.ROBOT_URDF), Tool.from_yaml(examples.TOOL_YAML)
    q = np.radians([p["q_deg"] for p in data["poses"]])
    rot, origin = robot.flange_poses(q)
    tcp = 1000.0 * (origin + rot @ tool.position_array[tool.index("A")])
    assert max(np.linalg.norm(tcp[i] - targets[ids[i][:2]]) for i in range(len(ids))) < 1e-6
    # one flange orientation for the five poses, the one the block states
    rpy = Rotation.from_matrix(rot).as_euler("xyz", degrees=True)
    assert np.allclose(rpy, rpy[0], atol=1e-6)
    assert np.allclose(block["rpy_deg"]["P3"], rpy[0], atol=1e-6)
    # the load carried at every visit: its weight, 250 kg
    assert all(abs(p["wrenches"][0][2] + 250 * 9.80665) < 1e-6 for p in data["poses"])


def test_a_cube_given_is_used(files):
    out = files / "given.json"
    assert main(["iso9283", "design", *ROBOT, "--tcp", "A", "--cube", "1800,0,1200,400",
                 "--cycles", "2", "--out", str(out)]) == 0
    block = json.loads(out.read_text())["iso9283"]
    assert block["cube"]["centre_mm"] == [1800, 0, 1200] and block["cube"]["edge_mm"] == 400
    assert block["targets_mm"]["P4"] == pytest.approx([1960, 160, 1360])


def _program_rows(path):
    """The pose rows of a joint program (not its home, via, approach or stop rows)."""
    rows = csv.DictReader(line for line in path.open() if not line.startswith("#"))
    return [r for r in rows if r["kind"] == "pose"]


def test_the_test_is_exported_in_cycle_order(design, tmp_path, capsys):
    assert main(["export", str(design), "--format", "csv", "--out", str(tmp_path)]) == 0
    rows = _program_rows(tmp_path / "doe_calib.csv")
    assert [r["pose"] for r in rows] == [f"{p}-{c:02d}" for c in range(1, CYCLES + 1)
                                         for p in POSES]
    # --turns design (the command's advice): each pose at one set of joint values
    assert main(["export", str(design), "--format", "csv", "--turns", "design", "--out",
                 str(tmp_path / "design_turns")]) == 0
    q = {}
    for r in _program_rows(tmp_path / "design_turns" / "doe_calib.csv"):
        q.setdefault(r["pose"][:2], set()).add(tuple(r[f"q{k}"] for k in range(1, 7)))
    assert all(len(v) == 1 for v in q.values())


def test_in_a_cell_the_poses_are_free_and_the_program_passes_the_check(tmp_path, capsys):
    out = tmp_path / "cell.json"
    assert main(["iso9283", "design", *ROBOT, "--tcp", "A", "--load", "250@0,0,200",
                 "--constraints", examples.CELL_YAML, "--cycles", "3", "--out", str(out)]) == 0
    assert json.loads(out.read_text())["constraints"]["collision"]["clearance_mm"] > 0
    capsys.readouterr()
    assert main(["export", str(out), "--format", "krl", "--turns", "design", "--out",
                 str(tmp_path / "prog"), "--json"]) == 0
    checked = json.loads(capsys.readouterr().out)["collision"]
    assert checked["moves"] > 15 and not checked["collisions"]


def _hand_report(paths, result_path, design_path):
    """Per session: pose → (AP, RP) of marker A's readings taken into the base frame by
    the result's base, computed here from the files themselves."""
    params = {p["name"]: p["value"] for p in json.loads(result_path.read_text())["parameters"]}
    t = np.array([params[f"base_{a}"] for a in "xyz"]) / 1000.0
    units = {p["name"]: p["unit"] for p in json.loads(result_path.read_text())["parameters"]}
    r = np.array([params[f"base_r{a}"] for a in "xyz"])
    r = np.radians(r) if units["base_rx"] == "deg" else r
    rot = Rotation.from_rotvec(r).as_matrix()
    targets = json.loads(design_path.read_text())["iso9283"]["targets_mm"]
    out = []
    for path in paths:
        points = {}
        rows = csv.DictReader(line for line in path.open() if not line.startswith("#"))
        for row in rows:
            if row["marker"] == "A":
                x = np.array([float(row[a]) for a in "xyz"]) / 1000.0
                points.setdefault(row["pose"][:2], []).append(1000.0 * rot.T @ (x - t))
        out.append({p: hand_ap_rp([list(v) for v in points[p]], targets[p]) for p in POSES})
    return out


def test_report_equals_a_hand_computation_side_by_side(files, design, result, capsys):
    """Before: the design's joint values; after: the program compensate makes of the
    targets CSV the design wrote beside it, both run on the simulated true robot."""
    before = _cycles(files, design, "before", 3)
    assert main(["compensate", "--result", str(result), "--targets",
                 str(files / "iso_targets.csv"), "--targets-frame", "base_link", "--tcp", "A",
                 "--out", str(files / "comp.csv"), "--format", "poses", "--program-out",
                 str(files / "comp")]) == 0
    after = _cycles(files, files / "comp" / "compensated.csv", "after", 4)
    out, html = files / "rep.json", files / "rep.html"
    assert main(["iso9283", "report", "--design", str(design), "--data", str(before),
                 str(after), "--result", str(result), "--tcp", "A", "--out", str(out),
                 "--report", str(html)]) == 0
    report = json.loads(out.read_text())
    assert report["format"] == "doe_calib.iso9283"
    assert [c["name"] for c in report["campaigns"]] == ["before", "after"]  # the sessions
    hand = _hand_report([before, after], result, design)
    for campaign, expected in zip(report["campaigns"], hand):
        for pose in POSES:
            got = campaign["poses"][pose]
            ap, _, rp = expected[pose]
            assert got["n"] == CYCLES
            assert abs(got["AP_mm"] - ap) < 1e-9 and abs(got["RP_mm"] - rp) < 1e-9
            assert got["RP_mm"] < 0.1 and got["RP_a_deg"] < 0.1  # σ 0.01 mm
            assert abs(got["AP_a_deg"]) < 1.0
        # the true joint offsets: AP of mm before, of the identification's error after
        aps = [campaign["poses"][p]["AP_mm"] for p in POSES]
        assert min(aps) > 0.3 if campaign["name"] == "before" else max(aps) < 0.05
        assert campaign["distance"]["poses"] == ["P2", "P4"]
        assert campaign["distance"]["n"] == CYCLES
    assert report["poses"] == report["campaigns"][-1]["poses"]
    text = html.read_text()
    assert "AP (mm)" in text and "data:image/png;base64" in text


def test_report_without_result_says_the_frame(files, design, capsys):
    data = files / "before.csv"
    if not data.exists():
        _cycles(files, design, "before", 3)
    capsys.readouterr()
    assert main(["iso9283", "report", "--design", str(design), "--data", str(data),
                 "--out", str(files / "raw.json"), "--json"]) == 0
    doc = json.loads(capsys.readouterr().out)
    assert "no --result" in doc["notes"][0] and set(doc["poses"]) == set(POSES)


def test_report_refuses_a_design_without_the_test(files, tmp_path, capsys):
    plain = tmp_path / "plain.json"
    data = json.loads((files / "iso.json").read_text())
    del data["iso9283"]
    plain.write_text(json.dumps(data))
    assert main(["iso9283", "report", "--design", str(plain), "--data",
                 str(files / "before.csv"), "--out", str(tmp_path / "r.json")]) == 2
    assert "not an ISO 9283 test design" in capsys.readouterr().err


def _test_poses(design):
    """The test poses' joint values (5, N), rad, and their targets (5, 3), mm."""
    design = json.loads(design.read_text())
    q = np.radians([p["q_deg"] for p in design["poses"][:5]])
    return q, np.array([design["iso9283"]["targets_mm"][p] for p in POSES])


def test_design_with_a_result_reaches_the_targets_on_the_identified_robot(identified_design,
                                                                          result):
    params = IdentificationResult.from_json(result).parameters
    robot = Robot.from_urdf(examples.ROBOT_URDF)
    q, targets = _test_poses(identified_design)
    # Pinocchio with the identified joint offsets and marker: on the targets
    rot, origin = robot.flange_poses(q + [params[f"dq_{j.name}"] for j in robot.joints])
    tcp = 1000.0 * (origin + rot @ [params[f"marker_A_{a}"] for a in "xyz"])
    assert np.abs(tcp - targets).max() < 1e-6
    predicted = json.loads(identified_design.read_text())["iso9283"]["predicted"]
    assert list(predicted) == POSES
    assert all(0 < p["AP_mm"] < 0.05 and len(p["std_mm"]) == 3 for p in predicted.values())


def test_predicted_std_equals_a_monte_carlo_of_the_joint_offsets(identified_design, result):
    """The joint offsets alone uncertain (the other rows of the covariance zeroed): 2000
    offset vectors drawn from it, the TCP by Pinocchio, in the robot base frame."""
    d = json.loads(result.read_text())
    free = [p["name"] for p in d["parameters"] if p["free"]]
    offsets = np.array([n.startswith("dq_") for n in free])
    cov = np.array(d["covariance_si"])
    cov[~offsets], cov[:, ~offsets] = 0.0, 0.0
    d["covariance_si"] = cov.tolist()
    res = IdentificationResult.from_dict(d)
    q, _ = _test_poses(identified_design)
    model, params = result_model(res)
    predicted = predicted_accuracy(model, res, Configurations.from_arrays(q), "A", POSES,
                                   CYCLES)
    robot = Robot.from_urdf(examples.ROBOT_URDF)
    names = [f"dq_{j.name}" for j in robot.joints]
    dq = np.tile([params[n] for n in names], (2000, 1))
    drawn = [names.index(n) for n in np.array(free)[offsets]]
    dq[:, drawn] = np.random.default_rng(0).multivariate_normal(
        dq[0, drawn], cov[np.ix_(offsets, offsets)] * res.sigma_ratio ** 2, 2000)
    marker = [params[f"marker_A_{a}"] for a in "xyz"]
    for k, pose in enumerate(POSES):
        rot, origin = robot.flange_poses(q[k] + dq)
        tcp = 1000.0 * (origin + rot @ marker)
        assert np.allclose(tcp.std(axis=0), predicted[pose]["std_mm"], rtol=0.15)
        rms = math.sqrt(tcp.var(axis=0).sum() + 3 * (res.sigma_ratio * res.sigma_mm) ** 2
                        / CYCLES)
        assert abs(predicted[pose]["AP_mm"] / rms - 1) < 0.15


def test_report_puts_the_predicted_beside_the_measured(files, identified_design, result):
    """Reached on the identified robot, the test measures about what its design predicted."""
    cycles = _cycles(files, identified_design, "identified", 5)
    out, html = files / "rep_predicted.json", files / "rep_predicted.html"
    assert main(["iso9283", "report", "--design", str(identified_design), "--data",
                 str(cycles), "--result", str(result), "--out", str(out), "--report",
                 str(html)]) == 0
    report = json.loads(out.read_text())
    predicted = json.loads(identified_design.read_text())["iso9283"]["predicted"]
    assert report["predicted"] == predicted
    assert all(report["poses"][p]["AP_mm"] < 4 * predicted[p]["AP_mm"] for p in POSES)
    assert "predicted" in html.read_text()
    # formats.md §14 names every key the design's block and the report write
    doc = (Path(__file__).parents[1] / "docs" / "formats.md").read_text(encoding="utf-8")
    block = json.loads(identified_design.read_text())["iso9283"]
    campaign = report["campaigns"][0]
    keys = {*block, *block["cube"], *predicted["P1"], *report, *campaign,
            *campaign["poses"]["P1"], *campaign["distance"]}
    assert not [k for k in keys if f"`{k}`" not in doc]
