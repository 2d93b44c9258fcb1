"""Measurement and design files: exact round trips, and a clear error for every bad input."""
import numpy as np
import pytest

from doe_calib import Configurations, DataError, Robot, Tool, build_model, examples, simulate
from doe_calib.io.csv_files import read_design, read_measurements, write_design, write_measurements
from doe_calib.model.simulate import random_configurations

HEADER = "pose,q1,q2,q3,q4,q5,q6,marker,x,y,z"
GOOD = "p1,10,-90,90,0,30,0,A,1000.5,20.25,1500"


@pytest.fixture(scope="module")
def rt():
    return Robot.from_urdf(examples.ROBOT_URDF), Tool.from_yaml(examples.TOOL_YAML)


def _write(tmp_path, *lines, name="m.csv"):
    p = tmp_path / name
    p.write_text("\n".join(lines) + "\n", encoding="utf-8")
    return p


def _error(tmp_path, rt, *lines, **kw):
    path = _write(tmp_path, *lines)
    with pytest.raises(DataError) as info:
        read_measurements(path, *rt, sigma=kw.pop("sigma", 2e-5), **kw)
    return str(info.value)


def test_round_trip_with_loads_missing_markers_and_temperature(rt, tmp_path):
    robot, tool = rt
    model = build_model(robot, tool, "joint_compliance")
    rng = np.random.default_rng(0)
    q = np.repeat(random_configurations(robot, 4, rng), 2, axis=0)
    w = np.zeros((8, 6))
    w[1::2] = rng.normal(size=(4, 6)) * 1000
    cfg = Configurations.from_arrays(q, w, env=rng.uniform(18, 25, (8, 1)),
                                     pose=np.repeat(["a", "b", "c", "d"], 2))
    meas = simulate(model, model.nominal(), cfg, 2e-5, rng)
    meas = meas.subset(np.arange(len(meas)) != 4)  # one marker not seen once
    write_measurements(tmp_path / "m.csv", meas, robot, tool)
    back = read_measurements(tmp_path / "m.csv", robot, tool)
    assert np.allclose(back.xyz, meas.xyz, rtol=0, atol=1e-15)
    assert np.allclose(back.configurations.q, meas.configurations.q, rtol=0, atol=1e-15)
    assert np.allclose(back.configurations.wrench, meas.configurations.wrench, atol=1e-12)
    assert np.allclose(back.configurations.env, meas.configurations.env)
    assert np.array_equal(back.config, meas.config) and np.array_equal(back.marker, meas.marker)
    assert np.allclose(back.sigma, 2e-5)
    assert back.line[0] == 3  # comment line, header, then the first reading


def test_prismatic_joints_in_mm(tmp_path):
    urdf = _write(tmp_path, '<robot name="pr"><link name="a"/><link name="b"/><link name="c"/>',
                  '<joint name="lift" type="prismatic"><parent link="a"/><child link="b"/>',
                  '<axis xyz="0 0 1"/><limit lower="0" upper="0.5" effort="1" velocity="1"/>',
                  '</joint><joint name="turn" type="revolute"><parent link="b"/><child link="c"/>',
                  '<origin xyz="0.3 0 0"/><axis xyz="0 0 1"/>',
                  '<limit lower="-3" upper="3" effort="1" velocity="1"/></joint></robot>',
                  name="pr.urdf")
    robot = Robot.from_urdf(urdf)
    tool = Tool.from_markers({"A": [0, 0, 10], "B": [10, 0, 0], "C": [0, 10, 0]})
    path = _write(tmp_path, "pose,q1,q2,marker,x,y,z", "1,250,45,A,1,2,3")
    meas = read_measurements(path, robot, tool, sigma=1e-5)
    assert meas.configurations.q[0] == pytest.approx([0.25, np.radians(45)])
    bad = _write(tmp_path, "pose,q1,q2,marker,x,y,z", "1,600,45,A,1,2,3")
    with pytest.raises(DataError, match=r"line 2, column 'q1' \(2\).*600 mm is outside"):
        read_measurements(bad, robot, tool, sigma=1e-5)


def test_design_round_trip(rt, tmp_path):
    robot, _ = rt
    rng = np.random.default_rng(3)
    cfg = Configurations.from_arrays(random_configurations(robot, 5, rng),
                                     rng.normal(size=(5, 6)), pose=list("abcde"))
    write_design(tmp_path / "d.csv", cfg, robot)
    back = read_design(tmp_path / "d.csv", robot)
    assert back.pose == cfg.pose
    assert np.allclose(back.q, cfg.q, atol=1e-15) and np.allclose(back.wrench, cfg.wrench)


@pytest.mark.parametrize("lines, where, words", [
    (["pose,q1,q2,q3,q4,q5,q6,marker,x,y", GOOD[:-5]], "line 1", "missing column(s) z"),
    ([HEADER + ",sigam", GOOD + ",0.02"], "column 'sigam' (12)", "unknown column"),
    ([HEADER + ",x", GOOD + ",1"], "column 12", "appears twice"),
    ([HEADER, GOOD + ",7"], "line 2", "12 fields where the header has 11"),
    ([HEADER, GOOD.replace("1000.5", "1,000.5")], "line 2", "fields where the header"),
    ([HEADER, GOOD.replace("20.25", "abc")], "line 2, column 'y' (10)", "'abc' is not a number"),
    ([HEADER, GOOD.replace("20.25", "nan")], "line 2, column 'y' (10)", "not a finite number"),
    ([HEADER, GOOD.replace(",A,", ",D,")], "line 2, column 'marker' (8)", "not in the tool"),
    ([HEADER, GOOD, "# comment", GOOD.replace(",A,", ",B,").replace(",30,", ",31,")],
     "line 4, column 'q5' (6)", "on line 2; all rows of a pose share q"),
    ([HEADER, GOOD.replace("-90", "-150")], "line 2, column 'q2' (3)", "outside the limits"),
    ([HEADER, GOOD.replace("p1", "")], "line 2, column 'pose' (1)", "empty pose id"),
    ([HEADER], "line 1", "no data rows"),
    ([HEADER, GOOD, GOOD], "line 3, column 'marker' (8)", "read twice"),
])
def test_bad_measurement_file(rt, tmp_path, lines, where, words):
    msg = _error(tmp_path, rt, *lines)
    assert "m.csv" in msg and where in msg and words in msg, msg


def test_no_sigma_anywhere_marks_sigma_unknown(rt, tmp_path):
    meas = read_measurements(_write(tmp_path, HEADER, GOOD), *rt, sigma=None)
    assert meas.sigma_estimated and np.isnan(meas.sigma).all()  # not given: no σ made up
    given = read_measurements(_write(tmp_path, HEADER, GOOD), *rt, sigma=2e-5)
    assert not given.sigma_estimated and given.sigma.tolist() == [2e-5]


def test_sigma_column_must_be_positive(rt, tmp_path):
    msg = _error(tmp_path, rt, HEADER + ",sigma", GOOD + ",0")
    assert "column 'sigma' (12)" in msg and "positive" in msg


def test_skip_bad_reports_every_dropped_row(rt, tmp_path):
    path = _write(tmp_path, HEADER, GOOD, GOOD.replace(",A,", ",Q,"),
                  GOOD.replace(",A,", ",B,").replace("20.25", "x"), GOOD.replace(",A,", ",C,"))
    meas = read_measurements(path, *rt, sigma=2e-5, skip_bad=True)
    assert len(meas) == 2 and list(meas.line) == [2, 5]
    assert len(meas.dropped) == 2
    assert "line 3" in meas.dropped[0] and "line 4" in meas.dropped[1]


def test_missing_file_and_bad_design(rt, tmp_path):
    robot, tool = rt
    with pytest.raises(DataError, match="cannot read"):
        read_measurements(tmp_path / "nope.csv", robot, tool, sigma=2e-5)
    path = _write(tmp_path, "pose,q1,q2,q3,q4,q5,q6,fz", "1,0,-90,90,0,0,0,heavy", name="d.csv")
    with pytest.raises(DataError, match=r"d.csv, line 2, column 'fz' \(8\)"):
        read_design(path, robot)


def test_tool_file_errors(tmp_path):
    bad = _write(tmp_path, "markers:", "  A: [1, 2]", "  B: [0, 0, 1]", "  C: [1, 0, 0]",
                 name="t.yaml")
    with pytest.raises(DataError, match=r"t.yaml, line 2, column 3: marker 'A' needs"):
        Tool.from_yaml(bad)
    bad = _write(tmp_path, "markers:", "  A: [1, 2, x]", name="t2.yaml")
    with pytest.raises(DataError, match=r"t2.yaml, line 2, column 13"):
        Tool.from_yaml(bad)
    two = _write(tmp_path, "markers:", "  A: [1, 2, 3]", "  B: [1, 2, 4]", name="t3.yaml")
    assert Tool.from_yaml(two).names == ("A", "B")  # one or two reflectors are a tool
    bad = _write(tmp_path, "markers: {}", name="t4.yaml")
    with pytest.raises(DataError, match="at least one marker"):
        Tool.from_yaml(bad)


def test_a_joint_a_hair_past_its_limit_is_a_warning_far_past_an_error(rt, tmp_path):
    robot, tool = rt
    upper = np.degrees(robot.upper[1])
    span = np.degrees(robot.upper[1] - robot.lower[1])
    rows = [f"p{i},10,{q2:.6g},90,0,30,0,A,1000.5,20.25,1500"
            for i, q2 in enumerate((upper + 0.01 * span, upper - 1.0))]
    meas = read_measurements(_write(tmp_path, HEADER, *rows), robot, tool, sigma=2e-5)
    assert len(meas) == 2 and meas.configurations.q[0, 1] > robot.upper[1]  # kept as measured
    (warning,) = meas.warnings
    assert "line 2" in warning and "'q2' (3)" in warning and "accepted as measured" in warning
    far = f"p9,10,{upper + 0.03 * span:.6g},90,0,30,0,A,1000.5,20.25,1500"
    message = _error(tmp_path, rt, HEADER, far)
    assert "line 2" in message and "'q2' (3)" in message and "outside the limits" in message
    design = _write(tmp_path, "pose,q1,q2,q3,q4,q5,q6",
                    f"d1,10,{upper + 0.01 * span:.6g},90,0,30,0", name="d.csv")
    with pytest.raises(DataError, match="outside the limits"):  # designs stay strict
        read_design(design, robot)


def test_sessions_from_a_column_or_from_several_files(rt, tmp_path):
    from doe_calib.diagnosis.cross_validation import make_folds
    from doe_calib.io.measurements import concatenate

    robot, tool = rt
    rows = [f"p{i},10,{-90 + i},90,0,30,0,{m},1000.5,20.25,1500,{'s1' if i < 3 else 's2'}"
            for i in range(6) for m in "ABC"]
    meas = read_measurements(_write(tmp_path, HEADER + ",session", *rows), robot, tool,
                             sigma=2e-5)
    assert list(meas.sessions) == ["s1"] * 3 + ["s2"] * 3
    folds = make_folds(meas)
    assert folds.grouping == "session" and len(folds.held) == 2
    assert [int(h.sum()) for h in folds.held] == [9, 9]
    one = read_measurements(_write(tmp_path, HEADER, *[r.rsplit(",", 1)[0] for r in rows[:9]],
                                   name="monday.csv"), robot, tool, sigma=2e-5)
    assert make_folds(one).grouping == "pose" and set(one.sessions) == {"monday"}
    both = concatenate([one, meas.subset(np.arange(9, 18))])
    assert list(dict.fromkeys(both.sessions)) == ["monday", "s2"]
    assert "session" in make_folds(both).description
    region = make_folds(meas, k=2, grouping="region")
    assert region.grouping == "region" and sum(int(h.sum()) for h in region.held) == 18
