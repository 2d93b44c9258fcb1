"""Design constraints: the file and its errors, the filter, and every designed pose checked
independently with Pinocchio forward kinematics and numpy."""
import numpy as np
import pinocchio as pin
import pytest

from doe_calib import examples
from doe_calib.design import LoadCase, read_constraints
from doe_calib.design.candidates.feasibility import build_feasibility
from doe_calib.design.optimal import optimal_design
from doe_calib.errors import DataError
from doe_calib.model.loads import GRAVITY
from doe_calib.model.simulate import random_configurations

LOAD = LoadCase(250.0, (0.0, 0.0, 0.2))
CELL = """\
# a measuring cell around the KR 270
joint_limits:
  a2: [-130, -15]
  a5: [-115, 115]
margin: 2
cartesian:
  keep_out:
    - {name: table, min: [800, -600, 0], max: [1800, 600, 800]}
  keep_in: {min: [-3000, -3000, -500], max: [3000, 3000, 3200]}
  floor: 150
  load_clearance: 250
line_of_sight:
  tracker: [-3000, 500, 1200]
  max_incidence: 70
  normals: {A: [0, 0, 1], B: [0, 0.1, 1]}
load_torque: {a2: 5000, a3: 4000, a5: 1500}
coverage: {joint: a2, bins: 5, min_bins: 5}
"""


@pytest.fixture(scope="module")
def cell(tmp_path_factory, robot6, tool6):
    path = tmp_path_factory.mktemp("cell") / "cell.yaml"
    path.write_text(CELL)
    return read_constraints(path, robot6, tool6)


class Independent:
    """Every constraint of ``CELL`` evaluated with Pinocchio and numpy (nominal robot)."""

    def __init__(self, robot, tool):
        self.model = pin.buildModelFromUrdf(examples.ROBOT_URDF)
        self.data = self.model.createData()
        self.frame = self.model.getFrameId(robot.flange)
        self.markers = tool.position_array

    def margins(self, q) -> dict:
        pin.framesForwardKinematics(self.model, self.data, q)
        placement = self.data.oMf[self.frame]
        rot, origin = placement.rotation, placement.translation
        jac = pin.computeFrameJacobian(self.model, self.data, q, self.frame,
                                       pin.LOCAL_WORLD_ALIGNED)
        markers = origin + self.markers @ rot.T
        com = origin + rot @ np.array(LOAD.com)
        force = np.array([0.0, 0.0, -LOAD.mass * GRAVITY])
        tau = jac.T @ np.r_[force, np.cross(rot @ np.array(LOAD.com), force)]
        lo, hi = np.array([0.8, -0.6, 0.0]), np.array([1.8, 0.6, 0.8])
        points = np.vstack([origin, markers, com])
        clear = np.r_[0.0, 0.0, 0.0, 0.0, 0.25]
        outside = np.linalg.norm(np.maximum(np.maximum(lo - points, points - hi), 0), axis=1)
        inside = np.all((points > lo) & (points < hi), axis=1)
        normals = np.array([[0, 0, 1], [0, 0.1, 1], [0, 0, 1]], float)
        normals /= np.linalg.norm(normals, axis=1, keepdims=True)
        sight = np.array([-3.0, 0.5, 1.2]) - markers
        cos = np.einsum("ij,ij->i", normals @ rot.T, sight) / np.linalg.norm(sight, axis=1)
        room = np.minimum(points - np.array([-3, -3, -0.5]), np.array([3, 3, 3.2]) - points)
        return {"keep_out": np.min(np.where(inside, -1.0, outside - clear)),
                "keep_in": np.min(room.min(axis=1) - clear),
                "floor": np.min(points[:, 2] - 0.15 - clear),
                "line_of_sight": np.min(np.radians(70) - np.arccos(np.clip(cos, -1, 1))),
                "load_torque": np.min(np.r_[5000, 4000, 1500] - np.abs(tau[[1, 2, 4]]))}


def test_file_is_read_in_si(cell, robot6):
    assert np.degrees(cell.lower[1]) == pytest.approx(-130) and cell.upper[4] == \
        pytest.approx(np.radians(115))
    assert cell.lower[0] == robot6.lower[0]  # joints not named keep the URDF limits
    lo, hi = cell.bounds(robot6)
    assert np.degrees(hi[1]) == pytest.approx(-17)
    assert cell.floor == pytest.approx(0.15) and cell.load_clearance == pytest.approx(0.25)
    assert cell.keep_out[0].name == "table" and cell.keep_out[0].upper[2] == pytest.approx(0.8)
    assert cell.line_of_sight.normals[1] == pytest.approx((0, 0.1 / np.sqrt(1.01),
                                                           1 / np.sqrt(1.01)))
    assert cell.torque_limits[1] == 5000 and np.isinf(cell.torque_limits[0])
    assert cell.coverage.min_bins == 5 and np.degrees(cell.coverage.edges[0]) == pytest.approx(-128)


@pytest.mark.parametrize("text, line, column, words", [
    ("joint_limit:\n  a2: [-130, -15]\n", 1, 1, "unknown entry 'joint_limit'"),
    ("joint_limits:\n  a9: [-130, -15]\n", 2, 3, "no joint 'a9'"),
    ("joint_limits:\n  a2: [-130, abc]\n", 2, 14, "'abc' is not a finite number"),
    ("joint_limits:\n  a2: [-170, -15]\n", 2, 7, "may only narrow"),
    ("joint_limits:\n  a2: [-15, -130]\n", 2, 7, "is not below"),
    ("margin: 90\n", 1, 9, "leaves no range for joint a2"),
    ("cartesian:\n  keep_out:\n    - {name: t, min: [0, 0, 0], max: [1, -1, 1]}\n", 3, 38,
     "every max coordinate"),
    ("cartesian:\n  floor: [1]\n", 2, 10, "not a finite number"),
    ("line_of_sight:\n  tracker: [1, 2, 3]\n  max_incidence: 60\n  normals: {Z: [0, 0, 1]}\n",
     4, 13, "no marker 'Z'"),
    ("line_of_sight:\n  tracker: [1, 2]\n  max_incidence: 60\n", 2, 12, "list of 3 numbers"),
    ("load_torque: {a2: -5}\n", 1, 19, "must be positive"),
    ("coverage: {joint: a2, bins: 3, min_bins: 4}\n", 1, 42, "min_bins"),
    ("joint_limits:\n  a2: [-130, -15\n", 3, 1, "not valid YAML"),
])
def test_bad_file_names_line_and_column(tmp_path, robot6, tool6, text, line, column, words):
    path = tmp_path / "bad.yaml"
    path.write_text(text)
    with pytest.raises(DataError) as err:
        read_constraints(path, robot6, tool6)
    assert (err.value.line, err.value.column) == (line, column), str(err.value)
    assert words in str(err.value) and str(path) in str(err.value)


def test_filter_agrees_with_pinocchio(cell, model6, robot6, tool6):
    """The CasADi filter removes exactly the poses the independent check rejects."""
    check = Independent(robot6, tool6)
    feas = build_feasibility(model6, model6.nominal().values, cell, [LOAD])
    q = random_configurations(robot6, 400, np.random.default_rng(3), margin=0.0)
    ok, violated = feas.feasible(q)
    names = {"keep_out": "keep_out:table", "keep_in": "keep_in", "floor": "floor",
             "line_of_sight": "line_of_sight", "load_torque": "load_torque"}
    for k in range(len(q)):
        for theirs, margin in check.margins(q[k]).items():
            if abs(margin) > 1e-6:  # not on the boundary
                assert violated[names[theirs]][k] == (margin < 0), (theirs, k, margin)
    assert all(v.any() for v in violated.values())  # each constraint bites
    assert 0 < ok.sum() < len(q)  # the cell constrains, and leaves room


def test_every_designed_pose_satisfies_every_constraint(cell, model6, robot6, tool6):
    d = optimal_design(model6, 15, [LOAD], candidates=3000, constraints=cell,
                       rng=np.random.default_rng(4))
    q = d.configurations.q[::2]
    lo, hi = cell.bounds(robot6)
    assert np.all(q >= lo - 1e-12) and np.all(q <= hi + 1e-12)
    check = Independent(robot6, tool6)
    for k in range(len(q)):
        margins = check.margins(q[k])
        assert margins["keep_out"] >= -1e-9, (k, margins)
        assert margins["keep_in"] >= -1e-9 and margins["floor"] >= -1e-9
        assert margins["line_of_sight"] >= -1e-9 and margins["load_torque"] >= -1e-6
    bins = np.digitize(np.degrees(q[:, 1]), np.linspace(-128, -17, 6)[1:-1])
    assert len(set(bins)) == 5 and d.coverage.met and d.coverage.bins_used == [0, 1, 2, 3, 4]
    c = d.candidates
    assert c.kept == 3000 and c.drawn - c.kept <= sum(c.removed.values())
    assert set(c.removed) == {"keep_out:table", "keep_in", "floor", "line_of_sight",
                                 "load_torque"}
    assert d.constraints["joint_limits"]["a2"] == pytest.approx([-130, -15])
    assert d.constraints["coverage"]["joint"] == "a2" and d.constraints["loads"] == ["250@0,0,200"]
    assert d.efficiency <= 1.0 and d.refinement["accepted"]


def test_cli_reports_a_bad_constraints_file(tmp_path, capsys):
    from doe_calib.cli import main

    bad = tmp_path / "cell.yaml"
    bad.write_text("coverage: {joint: a2, bins: 5}\nload_torque:\n  a7: 100\n")
    assert main(["design", "--robot", examples.ROBOT_URDF, "--tool", examples.TOOL_YAML,
                 "--constraints", str(bad), "--out", str(tmp_path / "d.json")]) == 2
    assert f"{bad}, line 3, column 3: no joint 'a7'" in capsys.readouterr().err
