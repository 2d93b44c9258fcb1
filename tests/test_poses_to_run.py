"""``export`` takes every file that holds poses (export/poses_to_run.py): a design, an
augmentation (its new poses, said so) and a compensation result (its q′, with --tool)."""
import json

import numpy as np
import pytest
from test_export_cell_program import events

from doe_calib import Robot, Tool, build_model, examples, simulate
from doe_calib.cli import main
from doe_calib.compensation.result import CompensationResult
from doe_calib.design.augment_result import AugmentResult
from doe_calib.errors import DataError
from doe_calib.export.poses_to_run import read_poses_to_run
from doe_calib.io.csv_files import read_design, write_measurements
from doe_calib.io.measurements import Configurations
from doe_calib.model.simulate import random_configurations

MODEL = "joint_offset+geometry"


def _places(q):
    """Each row of q (rad) as a tuple, mod 2π (the program may take q ± 2π on the KR 270's
    ±350° axes)."""
    return [tuple(r) for r in np.round(np.mod(np.asarray(q) + 1e-7, 2 * np.pi), 6)]


@pytest.fixture(scope="module")
def augmentation(tmp_path_factory):
    tmp = tmp_path_factory.mktemp("augment_export")
    robot, tool = Robot.from_urdf(examples.ROBOT_URDF), Tool.from_yaml(examples.TOOL_YAML)
    model = build_model(robot, tool, MODEL)
    rng = np.random.default_rng(7)
    cfg = Configurations.from_arrays(random_configurations(robot, 12, rng),
                                     pose=[f"m{i}" for i in range(12)])
    write_measurements(tmp / "m.csv", simulate(model, model.nominal().values, cfg, 2e-5, rng),
                       robot, tool)
    out = tmp / "next.json"
    assert main(["design", "--robot", examples.ROBOT_URDF, "--tool", examples.TOOL_YAML,
                 "--model", MODEL, "--augment", str(tmp / "m.csv"), "--poses", "3",
                 "--load", "150@0,0,200", "--candidates", "300", "--constraints",
                 examples.CELL_YAML, "--seed", "1", "--out", str(out)]) == 0
    return tmp, out, AugmentResult.from_json(out)


def test_an_augmentation_is_exported_as_its_new_poses(augmentation, capsys):
    tmp, path, result = augmentation
    new = result.configurations
    assert result.tool is not None and result.constraints["loads"] == ["150@0,0,200"]
    capsys.readouterr()
    assert main(["export", str(path), "--format", "poses", "--out", str(tmp / "plan.csv")]) == 0
    assert "runs the augmentation's 3 new poses (the 12 configurations measured before are " \
           "not run)" in capsys.readouterr().err
    plan = read_design(tmp / "plan.csv", result.robot)
    assert sorted(zip(plan.pose, _places(plan.q), map(tuple, np.round(plan.wrench, 6)))) \
        == sorted(zip(new.pose, _places(new.q), map(tuple, np.round(new.wrench, 6))))
    assert main(["export", str(path), "--format", "urscript", "--out", str(tmp / "ur")]) == 0
    err = capsys.readouterr().err
    assert "0 colliding" in err, err
    (script,) = (tmp / "ur").glob("*.script")
    assert "augmentation: its new poses only" in script.read_text()
    ev = events("urscript", [script])
    measured = np.radians([v for (k, v), (after, _) in zip(ev[:-1], ev[1:])
                           if k == "move" and after == "wait"])
    assert len(measured) == len(new)
    assert sorted(_places(measured)) == sorted(_places(new.q))


def test_a_compensation_result_runs_its_compensated_rows_in_order(tmp_path, capsys):
    robot = Robot.from_urdf(examples.ROBOT_URDF)
    rng = np.random.default_rng(3)
    q = random_configurations(robot, 3, rng)
    shifted = q + np.radians(0.1)
    converged = np.array([True, False, True])
    zeros = np.zeros(3)
    result = CompensationResult(
        robot=robot, model="joint_offset", tcp=np.zeros(3), tcp_marker=None,
        position_only=True, pose=("a", "b", "c"), q=q, q_compensated=shifted,
        wrench=np.zeros((3, 6)), target=np.zeros((3, 3)), residual=zeros,
        rotation_residual=zeros, predicted_std=zeros, converged=converged, note=("", "", ""))
    path = tmp_path / "comp.json"
    result.to_json(path)
    with pytest.raises(DataError, match="names no tool, whose markers the collision check"):
        read_poses_to_run(path)
    assert main(["export", str(path), "--tool", examples.TOOL_YAML, "--format", "poses",
                 "--no-collision", "--out", str(tmp_path / "c.csv"), "--json"]) == 0
    out = capsys.readouterr()
    assert json.loads(out.out)["source"] == "doe_calib.compensation"
    assert "runs the 3 compensated rows in their order (2 at q′, 1 not reached" in out.err
    plan = read_design(tmp_path / "c.csv", robot)
    assert plan.pose == ("a", "b", "c")
    assert _places(plan.q) == _places(np.where(converged[:, None], shifted, q))


def test_a_file_without_poses_is_refused_naming_the_formats(tmp_path):
    path = tmp_path / "r.json"
    path.write_text(json.dumps({"format": "doe_calib.result"}))
    with pytest.raises(DataError, match="holds no poses to run.*doe_calib.augment"):
        read_poses_to_run(path)
