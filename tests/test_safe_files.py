"""No command overwrites one of its inputs; values starting with '-' parse as values."""
import os
import shutil

import pytest

from doe_calib import examples
from doe_calib.cli import main

ROBOT = ["--robot", examples.ROBOT_URDF, "--tool", examples.TOOL_YAML]


def _run(argv) -> int:
    return main([str(a) for a in argv])


@pytest.fixture(scope="module")
def files(tmp_path_factory):
    """A copy of the KR 270 URDF, a campaign simulated on it and the result identified."""
    d = tmp_path_factory.mktemp("safe")
    shutil.copy(examples.ROBOT_URDF, d / "robot.urdf")
    robot = ["--robot", d / "robot.urdf", "--tool", examples.TOOL_YAML]
    assert _run(["simulate", *robot, "--model", "joint_offset", "--poses", "8", "--seed", "1",
                 "--out", d / "m.csv"]) == 0
    assert _run(["identify", *robot, "--model", "joint_offset", "--data", d / "m.csv",
                 "--out", d / "r.json"]) == 0
    return d


def _untouched(capsys, argv, victim, *words):
    """The command exits 2 with one error line holding ``words``; ``victim`` is unchanged."""
    before, stat = victim.read_bytes(), victim.stat()
    capsys.readouterr()
    assert _run(argv) == 2
    line = capsys.readouterr().err.strip().splitlines()[-1]
    assert line.startswith("error: ") and all(w in line for w in words), line
    assert victim.read_bytes() == before and victim.stat().st_mtime_ns == stat.st_mtime_ns


def test_predict_does_not_replace_its_data(files, capsys):
    m = files / "m.csv"
    _untouched(capsys, ["predict", "--result", files / "r.json", "--data", m, "--out", m], m,
               "--out", "is the input --data", "another name")


def test_identify_does_not_replace_its_csv_by_a_relative_path(files, capsys, monkeypatch):
    monkeypatch.chdir(files)
    _untouched(capsys, ["identify", "--robot", "robot.urdf", "--tool", examples.TOOL_YAML,
                        "--model", "joint_offset", "--data", "m.csv",
                        "--out", f"../{files.name}/m.csv"],
               files / "m.csv", "is the input --data m.csv")


def test_a_symlink_to_an_input_is_the_input(files, capsys):
    link = files / "link.csv"
    if not link.exists():
        os.symlink(files / "m.csv", link)
    _untouched(capsys, ["predict", "--result", files / "r.json", "--data", files / "m.csv",
                        "--out", link], files / "m.csv", "is the input --data")


def test_simulate_does_not_replace_the_urdf_or_the_tool(files, capsys, tmp_path):
    tool = tmp_path / "tool.yaml"
    shutil.copy(examples.TOOL_YAML, tool)
    _untouched(capsys, ["simulate", "--robot", files / "robot.urdf", "--tool", tool,
                        "--out", files / "robot.urdf"], files / "robot.urdf", "--robot")
    _untouched(capsys, ["simulate", "--robot", files / "robot.urdf", "--tool", tool,
                        "--out", files / "m2.csv", "--truth-out", tool], tool, "--tool")


def test_export_urdf_does_not_replace_its_source_urdf(files, capsys):
    urdf = files / "robot.urdf"
    _untouched(capsys, ["export-urdf", "--result", files / "r.json", "--out", urdf], urdf,
               "the result's robot", "another name")


def test_export_urdf_does_not_replace_the_result_with_its_yaml(files, capsys):
    shutil.copy(files / "r.json", files / "r.yaml")   # the YAML beside out.urdf is out.yaml
    _untouched(capsys, ["export-urdf", "--result", files / "r.yaml", "--out",
                        files / "r.urdf"], files / "r.yaml", "r.yaml: is the input --result")


@pytest.mark.parametrize("extra", [["--tracker", "-300,200,0,0,-10,5"],
                                   ["--tracker=-300,200,0,0,-10,5"],
                                   ["--load", "5@-100,0,200"], ["--load", "5@-100,-1,-2"]])
def test_negative_numbers_in_comma_options(extra, tmp_path, capsys):
    out = tmp_path / "m.csv"
    assert _run(["simulate", *ROBOT, "--model", "joint_offset", "--poses", "3", "--seed", "2",
                 *extra, "--out", out]) == 0, capsys.readouterr().err
    assert out.is_file()


def test_tracker_placement_with_negative_numbers_is_used(tmp_path):
    import json
    truth = tmp_path / "t.json"
    assert _run(["simulate", *ROBOT, "--model", "joint_offset", "--poses", "3", "--seed", "2",
                 "--tracker", "-300,200,-50,0,0,0", "--out", tmp_path / "m.csv",
                 "--truth-out", truth]) == 0
    rows = {r["name"]: r["value"] for r in json.loads(truth.read_text())["parameters"]}
    assert (rows["base_x"], rows["base_y"], rows["base_z"]) == pytest.approx((-300, 200, -50))
