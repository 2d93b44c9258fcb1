"""The column-at-a-time reader gives exactly what the row-by-row reader gives, or steps aside."""
import numpy as np
import pytest

from doe_calib import Configurations, Robot, Tool, build_model, examples, simulate
from doe_calib.io.column_reader import read_columns
from doe_calib.io.csv_files import read_measurements, write_measurements
from doe_calib.io.table import read_table
from doe_calib.model.simulate import random_configurations


@pytest.fixture(scope="module")
def rt():
    return Robot.from_urdf(examples.ROBOT_URDF), Tool.from_yaml(examples.TOOL_YAML)


def _same(a, b):
    for f in ("config", "marker", "xyz", "sigma", "line"):
        assert np.array_equal(getattr(a, f), getattr(b, f), equal_nan=True), f
    for f in ("q", "wrench", "env"):
        assert np.array_equal(getattr(a.configurations, f), getattr(b.configurations, f),
                              equal_nan=True), f
    assert a.configurations.pose == b.configurations.pose
    assert a.session == b.session and a.warnings == b.warnings
    assert a.sigma_estimated == b.sigma_estimated


def _rich_file(rt, tmp_path):
    """Loads, temperatures, two sessions, a missing reading, shuffled rows, a σ column."""
    robot, tool = rt
    model = build_model(robot, tool, "joint_compliance")
    rng = np.random.default_rng(4)
    q = np.repeat(random_configurations(robot, 6, rng), 2, axis=0)
    w = np.zeros((12, 6))
    w[1::2] = rng.normal(size=(6, 6)) * 1000
    cfg = Configurations.from_arrays(q, w, env=rng.uniform(18, 25, (12, 1)),
                                     pose=np.repeat([f"p{i}" for i in range(6)], 2))
    meas = simulate(model, model.nominal(), cfg, 2e-5, rng)
    meas = meas.subset(np.arange(len(meas)) != 7)
    path = tmp_path / "rich.csv"
    write_measurements(path, meas, robot, tool)
    lines = path.read_text().splitlines()
    head = next(i for i, s in enumerate(lines) if s.startswith("pose"))
    body = lines[head + 1:]
    # σ of every third row 0.025 mm, the others empty (taking --sigma); a session column
    at = lines[head].split(",").index("sigma")
    rows = []
    for k, s in enumerate(body):
        cells = s.split(",")
        cells[at] = "" if k % 3 else "0.025"
        rows.append(",".join(cells) + f",{'mon' if k < 15 else 'tue'}")
    path.write_text("\n".join(lines[:head] + [lines[head] + ",session"] + rows) + "\n")
    return path


def test_a_rich_file_reads_the_same_both_ways(rt, tmp_path):
    path = _rich_file(rt, tmp_path)
    table = read_table(path)
    assert read_columns(table, *rt, 0.02, True, False, "rich") is not None  # the fast path ran
    fast = read_measurements(path, *rt, sigma_mm=0.02)
    rows = read_measurements(path, *rt, sigma_mm=0.02, skip_bad=True)  # row by row
    _same(fast, rows)
    assert set(fast.sigma) == {2.5e-5, 2e-5} and list(dict.fromkeys(fast.session)) == ["mon",
                                                                                         "tue"]


def test_semicolons_decimal_commas_and_approach_columns(rt, tmp_path):
    robot, tool = rt
    lines = ["pose;q1;q2;q3;q4;q5;q6;marker;x;y;z;" + ";".join(f"approach{k}" for k in
                                                                 range(1, 7))]
    for i, m in [(0, "A"), (0, "B"), (1, "A"), (1, "C")]:
        lines.append(f"p{i};10,5;-9{i},25;90;0;30;0;{m};1000,5;20,25;1500;1;-1;0;1;1;-1")
    path = tmp_path / "semi.csv"
    path.write_text("\n".join(lines) + "\n")
    assert read_columns(read_table(path), *rt, 0.02, True, True, "semi") is not None
    fast = read_measurements(path, *rt, sigma_mm=0.02)
    _same(fast, read_measurements(path, *rt, sigma_mm=0.02, skip_bad=True))
    assert np.allclose(fast.configurations.q[1, :2], np.radians([10.5, -91.25]))
    assert np.array_equal(fast.configurations.approach[0], [1, -1, 0, 1, 1, -1])


@pytest.mark.parametrize("row, why", [
    ("p1,10,-90,90,0,30,0,A,1000.5,20.25,nan", "a non-finite number"),
    ("p1,10,-90,90,0,30,0,Z,1000.5,20.25,1500", "an unknown marker"),
    ("p1,10,-90,90,0,30,0,A,1000.5,20.25", "a short row"),
    ("p1,10,-89,90,0,30,0,B,1000.5,20.25,1500", "a pose whose rows disagree on q"),
    ("p1,10,-90,90,0,30,0,A,1000.5,20.25,1501", "a marker read twice"),
    ("p1,10,-90,90,0,30,0,B,,20.25,1500", "an empty coordinate"),
])
def test_anything_unusual_goes_to_the_row_reader(rt, tmp_path, row, why):
    path = tmp_path / "odd.csv"
    path.write_text("pose,q1,q2,q3,q4,q5,q6,marker,x,y,z\n"
                    "p1,10,-90,90,0,30,0,A,1000.5,20.25,1500\n" + row + "\n")
    assert read_columns(read_table(path), *rt, 0.02, True, False, "odd") is None, why


def test_a_reading_past_a_limit_keeps_its_warning(rt, tmp_path):
    robot, tool = rt
    upper = np.degrees(robot.upper[1]) + 0.5
    path = tmp_path / "limit.csv"
    path.write_text("pose,q1,q2,q3,q4,q5,q6,marker,x,y,z\n"
                    f"p1,10,{upper:.6g},90,0,30,0,A,1000.5,20.25,1500\n")
    meas = read_measurements(path, robot, tool, sigma_mm=0.02)
    assert len(meas.warnings) == 1 and "accepted as measured" in meas.warnings[0]
