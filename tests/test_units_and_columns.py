"""Files in the wrong units and extra columns: named as such, with the fix."""
import warnings

import numpy as np
import pytest

from doe_calib import Robot, Tool, examples
from doe_calib.cli import main
from doe_calib.errors import DataError, DataWarning
from doe_calib.io.csv_files import read_design, read_measurements

HEADER = "pose,q1,q2,q3,q4,q5,q6,marker,x,y,z"
ROWS = ["p1,10,-90,90,0,30,0,A,1000.5,20.25,1500", "p1,10,-90,90,0,30,0,B,1001.5,21.25,1501",
        "p2,20,-80,80,10,20,5,A,1100.5,30.25,1400"]


@pytest.fixture(scope="module")
def rt():
    return Robot.from_urdf(examples.ROBOT_URDF), Tool.from_yaml(examples.TOOL_YAML)


def _write(path, *lines):
    path.write_text("\n".join(lines) + "\n")
    return path


def _untouched_cli(capsys, argv, victim, *words):
    before, stat = victim.read_bytes(), victim.stat()
    capsys.readouterr()
    assert main([str(a) for a in argv]) == 2
    line = capsys.readouterr().err.strip().splitlines()[-1]
    assert line.startswith("error: ") and all(w in line for w in words), line
    assert victim.read_bytes() == before and victim.stat().st_mtime_ns == stat.st_mtime_ns


def test_an_extra_column_is_ignored_with_a_note(rt, tmp_path):
    robot, tool = rt
    plain = read_measurements(_write(tmp_path / "a.csv", HEADER, *ROWS), robot, tool)
    stamped = [r + f",2026-12-01T10:0{i}:00" for i, r in enumerate(ROWS)]
    meas = read_measurements(_write(tmp_path / "b.csv", HEADER + ",timestamp", *stamped),
                             robot, tool)
    assert np.array_equal(meas.xyz, plain.xyz) and np.array_equal(meas.configurations.q,
                                                                  plain.configurations.q)
    assert "'timestamp' ignored" in meas.warnings[0] and "b.csv" in meas.warnings[0]
    assert not any("timestamp" in w for w in plain.warnings)


def test_an_extra_column_in_a_design_is_ignored_with_a_warning(rt, tmp_path):
    robot, _ = rt
    path = _write(tmp_path / "d.csv", "pose,q1,q2,q3,q4,q5,q6,comment", "a,10,-90,90,0,30,0,x",
                  "b,20,-80,80,10,20,5,y")
    with pytest.warns(DataWarning, match="'comment' ignored"):
        cfg = read_design(path, robot)
    assert cfg.pose == ("a", "b")


@pytest.mark.parametrize("column, hint", [("sigam", "did you mean 'sigma'"),
                                          ("Temperatur", "did you mean 'temperature'"),
                                          ("q7", "no such joint")])
def test_a_typo_of_a_known_column_is_still_an_error(rt, tmp_path, column, hint):
    robot, tool = rt
    path = _write(tmp_path / "m.csv", HEADER + f",{column}", *(r + ",1" for r in ROWS))
    with pytest.raises(DataError, match=hint) as info:
        read_measurements(path, robot, tool)
    assert f"column '{column}' (12)" in str(info.value)


def test_joint_values_in_radians_are_named(rt, tmp_path, capsys):
    robot, tool = rt
    rad = [",".join([r.split(",")[0]] + [f"{np.radians(float(v)):.5f}" for v in
                                          r.split(",")[1:7]] + r.split(",")[7:]) for r in ROWS]
    rad.append("p3,0.5,-1.2,1.0,0.3,0.2,0.1,A,900,10,1300")
    path = _write(tmp_path / "m.csv", HEADER, *rad)
    # q2 of the KR 270 lies in [-140, -5] deg: -1.57 read as degrees is outside, as rad inside
    with pytest.raises(DataError, match="read as radians .* inside: the file is likely in "
                                        "radians, and q must be in degrees"):
        read_measurements(path, robot, tool)
    # a robot whose limits hold zero: every value is inside, all of them tiny in degrees
    path = _write(tmp_path / "m2.csv", "pose,q1,q2,q3,marker,x,y,z",
                  "a,0.5,-1.2,1.0,A,900,10,1300", "b,1.5,0.2,-0.4,A,950,10,1200",
                  "c,-2.9,0.7,0.1,A,800,10,1100")
    three = (Robot.from_urdf(examples.THREE_DOF_URDF), Tool.from_yaml(examples.THREE_DOF_TOOL_YAML))
    with pytest.raises(DataError, match="within ±2.9 deg while the limits span up to 360 deg: "
                                        "the file is likely in radians; q must be in degrees"):
        read_measurements(path, *three)
    out = _write(tmp_path / "r.json", "{}")
    _untouched_cli(capsys, ["identify", "--robot", examples.THREE_DOF_URDF, "--tool",
                            examples.THREE_DOF_TOOL_YAML, "--model", "joint_offset", "--data", path,
                            "--out", out], out, "likely in radians")


def test_a_design_in_radians_is_named(tmp_path):
    robot = Robot.from_urdf(examples.THREE_DOF_URDF)
    path = _write(tmp_path / "d.csv", "pose,q1,q2,q3", "a,0.1,-90,0.5", "b,0.2,-80,0.4",
                  "c,0.3,-70,0.3")
    assert len(read_design(path, robot)) == 3   # one joint in degrees: not radians
    path = _write(tmp_path / "d2.csv", "pose,q1,q2,q3", "a,0.1,-1.5,0.5", "b,0.2,-1.4,0.4",
                  "c,0.3,-1.3,0.3")
    with pytest.raises(DataError, match="d2.csv: every revolute joint value is within ±1.5 deg"
                                        ".* likely in radians"):
        read_design(path, robot)


def test_a_tool_file_in_metres_is_named_with_the_fix(tmp_path, capsys):
    path = _write(tmp_path / "tool.yaml", "markers:", "  A: [0.15, 0.0, 0.08]",
                  "  B: [-0.075, 0.13, 0.08]", "  C: [-0.075, -0.13, 0.08]")
    with pytest.raises(DataError, match=r"looks like metres; marker positions must be in mm "
                                        r"\(write 0.15 as 150\)"):
        Tool.from_yaml(path)
    _untouched_cli(capsys, ["simulate", "--robot", examples.ROBOT_URDF, "--tool", path,
                            "--out", tmp_path / "m.csv"], path, "tool.yaml", "metres")
    assert not (tmp_path / "m.csv").exists()
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        assert Tool.from_yaml(examples.TOOL_YAML).names == ("A", "B", "C")
