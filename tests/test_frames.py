"""Frames a cell file and compensation targets may be written in (UR's base vs base_link)."""
import independent_sim as sim
import numpy as np
import pinocchio as pin
import pytest

from doe_calib import Configurations, IdentificationResult, Robot, Tool, build_model, examples
from doe_calib.cli import main
from doe_calib.compensation import read_targets
from doe_calib.design import read_constraints
from doe_calib.errors import DataError, OptionError
from doe_calib.model.evaluation import evaluate

CELL_BASE_LINK = """\
cartesian:
  floor: -100
  keep_out:
    - {name: wall, min: [900, -2000, -100], max: [1100, 2000, 2000]}
    - {name: table, min: [200, -400, -100], max: [800, 300, -50]}
  keep_in: {min: [-1500, -1400, -100], max: [1200, 1300, 2000]}
line_of_sight:
  tracker: [2500, 300, 800]
  max_incidence: 70
"""
# the same cell as the UR pendant reads it: x and y flipped (base = base_link turned about z)
CELL_BASE = """\
frame: base
cartesian:
  floor: -100
  keep_out:
    - {name: wall, min: [-1100, -2000, -100], max: [-900, 2000, 2000]}
    - {name: table, min: [-800, -300, -100], max: [-200, 400, -50]}
  keep_in: {min: [-1200, -1300, -100], max: [1500, 1400, 2000]}
line_of_sight:
  tracker: [-2500, -300, 800]
  max_incidence: 70
"""
MARKERS = {"A": [100, 0, 50], "B": [-50, 86, 50], "C": [-50, -86, 50]}


@pytest.fixture(scope="module")
def ur10():
    path = sim.ur10_urdf()
    if path is None:
        pytest.skip("example-robot-data (UR10 URDF) is not installed")
    return Robot.from_urdf(path, flange="tool0"), Tool.from_markers(MARKERS, flange="tool0"), path


def _same(a, b):
    assert a.floor == pytest.approx(b.floor, abs=1e-12)
    for x, y in zip((*a.keep_out, a.keep_in), (*b.keep_out, b.keep_in)):
        assert x.name == y.name
        assert np.allclose(x.lower, y.lower, atol=1e-12) and np.allclose(x.upper, y.upper,
                                                                         atol=1e-12)
    assert np.allclose(a.line_of_sight.tracker, b.line_of_sight.tracker, atol=1e-12)


def test_a_ur_cell_written_in_base_is_the_mirrored_one_in_base_link(ur10, tmp_path):
    robot, tool, _ = ur10
    (tmp_path / "a.yaml").write_text(CELL_BASE_LINK)
    (tmp_path / "b.yaml").write_text(CELL_BASE)
    (tmp_path / "c.yaml").write_text("frame: base_link\n" + CELL_BASE_LINK)
    plain = read_constraints(tmp_path / "a.yaml", robot, tool)
    _same(read_constraints(tmp_path / "b.yaml", robot, tool), plain)
    _same(read_constraints(tmp_path / "c.yaml", robot, tool), plain)
    # without the frame, the pendant's numbers land mirrored: the wall behind the robot
    wrong = read_constraints(tmp_path / "b.yaml", robot, tool).keep_out[0]
    assert wrong.lower[0] == pytest.approx(0.9)
    (tmp_path / "d.yaml").write_text(CELL_BASE.replace("frame: base\n", ""))
    assert read_constraints(tmp_path / "d.yaml", robot, tool).keep_out[0].upper[0] == \
        pytest.approx(-0.9)


def test_base_on_a_urdf_without_it_is_the_ur_convention(tmp_path):
    robot, tool = Robot.from_urdf(examples.ROBOT_URDF), Tool.from_yaml(examples.TOOL_YAML)
    (tmp_path / "b.yaml").write_text(CELL_BASE)
    (tmp_path / "a.yaml").write_text(CELL_BASE_LINK)
    _same(read_constraints(tmp_path / "b.yaml", robot, tool),
          read_constraints(tmp_path / "a.yaml", robot, tool))


def test_a_moving_or_unknown_frame_is_refused_by_line(ur10, tmp_path):
    robot, tool, _ = ur10
    (tmp_path / "m.yaml").write_text("frame: forearm_link\n" + CELL_BASE_LINK)
    with pytest.raises(DataError, match="m.yaml, line 1.*moves with joint elbow_joint"):
        read_constraints(tmp_path / "m.yaml", robot, tool)
    (tmp_path / "u.yaml").write_text("frame: bse\n" + CELL_BASE_LINK)
    with pytest.raises(DataError, match="no fixed frame 'bse'.*base, base_link"):
        read_constraints(tmp_path / "u.yaml", robot, tool)


def _result(robot, tool, rng):
    """A result at nominal geometry whose base pose puts the robot 2 m from the tracker."""
    model = build_model(robot, tool, "joint_offset")
    axis = rng.normal(size=3)
    params = model.nominal().updated(**dict(zip(
        ["base_x", "base_y", "base_z", "base_rx", "base_ry", "base_rz"],
        [1.5, -1.2, 0.3, *(axis / np.linalg.norm(axis) * 2.0)])))
    n = int(params.free.sum())
    return model, IdentificationResult(robot, tool, model.spec, "point", params,
                                       np.eye(n) * 1e-12, 1.0, {"rms_mm": 0.0}, {}, 30, 0.02)


def test_targets_in_a_named_frame_land_where_pinocchio_puts_them(ur10, tmp_path):
    robot, tool, path = ur10
    rng = np.random.default_rng(4)
    model, result = _result(robot, tool, rng)
    q = sim.random_configurations(sim.Chain.from_urdf(path, "tool0"), 5, rng)
    # the flange origin at each q, written by hand in the frame 'base' with Pinocchio's own
    # placements: p_base = oMf[base]⁻¹ · oMf[tool0]
    pm = pin.buildModelFromUrdf(str(path))
    data = pm.createData()
    chain = sim.Chain.from_urdf(path, "tool0")
    rows = []
    for i, qi in enumerate(q):
        pin.framesForwardKinematics(pm, data, chain.full(qi))
        p = data.oMf[pm.getFrameId("base")].actInv(data.oMf[pm.getFrameId("tool0")]).translation
        rows.append(",".join([f"p{i}", *(f"{v:.9f}" for v in np.degrees(qi)),
                              *(f"{v:.9f}" for v in p * 1000.0)]))
    csv = tmp_path / "targets.csv"
    csv.write_text("pose,q1,q2,q3,q4,q5,q6,x,y,z\n" + "\n".join(rows) + "\n")
    got = read_targets(csv, robot, "base", result).positions
    expected = np.asarray(evaluate(model.point, Configurations.from_arrays(q),
                                   result.parameters.values, np.zeros(3))[0])[:, :, 0]
    assert np.abs(got - expected).max() < 1e-8
    # read as tracker coordinates (the default) they would be metres off
    assert np.abs(read_targets(csv, robot).positions - expected).max() > 0.5
    with pytest.raises(OptionError, match="need the identification result"):
        read_targets(csv, robot, "base")


def test_cli_targets_frame(ur10, tmp_path, capsys):
    robot, tool, path = ur10
    _, result = _result(robot, tool, np.random.default_rng(5))
    result.to_json(tmp_path / "r.json")
    csv = tmp_path / "t.csv"
    csv.write_text("pose,q1,q2,q3,q4,q5,q6,x,y,z\na,0,-90,90,-90,-90,0,-500,100,600\n")
    argv = ["compensate", "--result", tmp_path / "r.json", "--targets", csv, "--tcp", "A",
            "--out", tmp_path / "c.csv", "--targets-frame", "shoulder_link"]
    assert main([str(a) for a in argv]) == 2
    assert "moves with joint shoulder_pan_joint" in capsys.readouterr().err
    assert not (tmp_path / "c.csv").exists()
