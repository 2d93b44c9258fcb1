"""The measurement reader converts whole columns (one numpy.loadtxt pass over a clean table's
text, configurations keyed by integer codes) to the file's values as Python's csv module and
float() read them, and names the first bad value of a large file with its line and column."""
import csv
import sys

import numpy as np
import pytest

from doe_calib import Robot, Tool, examples
from doe_calib.errors import DataError
from doe_calib.io.csv_files import read_measurements
from doe_calib.io.table import read_table

HEADER = ("pose,q1,q2,q3,q4,q5,q6,fx,fy,fz,mx,my,mz,temperature,marker,x,y,z,sigma,session,"
          + ",".join(f"approach{k}" for k in range(1, 7)))


@pytest.fixture(scope="module")
def rt():
    return Robot.from_urdf(examples.ROBOT_URDF), Tool.from_yaml(examples.TOOL_YAML)


def _rows(rng, n_poses=40):
    """Rows with every column kind: loads (some -0.0, some repeated), temperatures, σ, two
    sessions, approach directions, markers missing, poses named as text."""
    rows = []
    for p in range(n_poses):
        q = rng.uniform([-60, -120, -60, -60, -60, -60], [60, -20, 60, 60, 60, 60]).tolist()
        for load in range(2):
            w = [0.0, -0.0, -2451.6625 * load, 16.5 * load, -473.29 * load, 0.0]
            temp = f"{rng.uniform(18, 25):.3f}"
            appr = rng.choice([-1, 0, 1], 6)
            for m in "ABC"[: 3 - (p % 5 == 0)]:
                xyz = (rng.normal(size=3) * 2000).tolist()
                rows.append([f"P-{p:03d}", *map(repr, q), *map(repr, w), temp, m,
                             *map(repr, xyz), repr(float(rng.uniform(0.01, 0.05))),
                             "mon" if p < 25 else "tue", *map(str, appr)])
    return rows


def _write(path, rows, header=HEADER, comments=True, newline="\n"):
    lines = ["# a measurement file", header]
    for k, r in enumerate(rows):
        if comments and k % 17 == 3:
            lines += ["", "# a comment between rows"]
        lines.append(",".join(r))
    path.write_bytes((newline.join(lines) + newline).encode())
    return path


def _independent(path, robot):
    """The file read with the csv module and float(): readings' xyz, σ (m) and line numbers."""
    with open(path, newline="") as fh:
        lines = fh.read().splitlines()
    kept = [(n, s) for n, s in enumerate(lines, 1) if s.strip() and not s.startswith("#")]
    header = next(csv.reader([kept[0][1]]))
    body = [(n, next(csv.reader([s]))) for n, s in kept[1:]]
    col = {c: i for i, c in enumerate(header)}
    xyz = np.array([[float(f[col[c]]) for c in "xyz"] for _, f in body]) / 1000.0
    sigma = np.array([float(f[col["sigma"]]) for _, f in body]) / 1000.0
    q_deg = np.array([[float(f[col[f"q{k}"]]) for k in range(1, 7)] for _, f in body])
    return xyz, sigma, np.array([n for n, _ in body]), q_deg / robot.display_factors


@pytest.mark.parametrize("newline", ["\n", "\r\n"])
def test_a_clean_file_is_read_from_its_text_the_same_as_row_by_row(rt, tmp_path, newline):
    rng = np.random.default_rng(5)
    path = _write(tmp_path / "clean.csv", _rows(rng), newline=newline)
    assert read_table(path).clean
    fast = read_measurements(path, *rt)
    xyz, sigma, line, q = _independent(path, rt[0])
    assert xyz.tobytes() == fast.xyz.tobytes() and sigma.tobytes() == fast.sigma.tobytes()
    assert np.array_equal(line, fast.line)
    assert q.tobytes() == fast.configurations.q[fast.config].tobytes()
    # the configurations: (pose, load, temperature, approach, session) in order of appearance
    assert len(fast.configurations) == 80 and fast.configurations.pose[:3] == ("P-000",) * 2 + \
        ("P-001",)
    assert list(dict.fromkeys(fast.session)) == ["mon", "tue"]


def test_a_tab_separated_file_with_decimal_commas(rt, tmp_path):
    rows = _rows(np.random.default_rng(7), 6)
    lines = [HEADER.replace(",", "\t")] + ["\t".join(c.replace(".", ",") for c in r)
                                           for r in rows]
    path = tmp_path / "tabs.csv"
    path.write_text("\n".join(lines) + "\n")
    table = read_table(path)
    assert table.decimal_comma and not table.clean
    fast = read_measurements(path, *rt)
    assert fast.xyz[0, 0] == float(rows[0][15]) / 1000.0


def test_every_kind_of_white_space_is_seen_and_stripped(tmp_path):
    """Table.clean notices each character str.strip removes, and the fields are stripped."""
    spaces = [c for c in map(chr, range(sys.maxunicode + 1))
              if c.isspace() and len(("a" + c + "b").splitlines()) == 1]
    assert len(spaces) > 10
    body = "".join(f"p{k},{c}1.5{c},x\n" for k, c in enumerate(spaces))
    path = tmp_path / "spaces.csv"
    path.write_text("pose,v,w\n" + body, encoding="utf-8")
    table = read_table(path)
    assert not table.clean
    assert all(f == [f"p{k}", "1.5", "x"] for k, (_, f) in enumerate(table.rows))
    for k, c in enumerate(spaces):
        one = tmp_path / f"one{k}.csv"
        one.write_text(f"pose,v\np1,2{c}\n", encoding="utf-8")
        assert not read_table(one).clean, hex(ord(c))
    assert read_table(_write(tmp_path / "ok.csv", [["p1", "2"]], "pose,v")).clean


def test_a_bad_cell_in_a_clean_file_is_named_with_its_line_and_column(rt, tmp_path):
    rows = _rows(np.random.default_rng(8), 10)
    rows[23][16] = "12x"
    path = _write(tmp_path / "bad.csv", rows, comments=False)
    with pytest.raises(DataError) as err:
        read_measurements(path, *rt)
    msg = str(err.value)
    assert "bad.csv" in msg and "line 26" in msg and "'y' (17)" in msg, msg


@pytest.mark.parametrize("column, text, words", [
    (16, "12x", "'12x' is not a number"),         # y, deep in a clean file
    (13, "200", "200 °C is not a plausible temperature"),
    (18, "-0.02", "σ must be positive"),
])
def test_the_first_bad_value_deep_in_a_large_file_is_named(rt, tmp_path, column, text, words):
    """20 000 readings; the bad value on reading 15 001 and a later one: the first is named."""
    base = _rows(np.random.default_rng(9), 2500)[:6667]
    rows = [r[:] for _ in range(3) for r in base]  # 20 001 rows; sessions tell poses apart
    for k, r in enumerate(rows):
        r[19] = f"s{k // 6667}"
    rows[15000][column], rows[17000][16] = text, "bad"
    path = _write(tmp_path / "large.csv", rows, comments=False)
    with pytest.raises(DataError) as err:
        read_measurements(path, *rt)
    name = HEADER.split(",")[column]
    assert str(err.value) == (f"{path}, line 15003, column '{name}' ({column + 1}): "
                              + str(err.value).split(": ", 1)[1])
    assert words in str(err.value)


def test_each_bad_row_is_told_by_its_first_problem(rt, tmp_path):
    """Checked a column at a time, told as read along each row: in a row with several
    problems the first in the row's order; a repeat against the first good reading."""
    good = "p1,10,-90,90,0,30,0,A,1000.5,20.25,1500"
    path = _write(tmp_path / "bad.csv", [r.split(",") for r in [
        good,
        good.replace(",A,", ",B,").replace(",30,", ",31,").replace("20.25", "abc"),  # q5, y
        good.replace("1500", "1501"),                                              # A again
        good.replace(",A,", ",Z,").replace("1000.5", "x"),                         # marker, x
        good.replace(",A,", ",C,")]], "pose,q1,q2,q3,q4,q5,q6,marker,x,y,z", comments=False)
    meas = read_measurements(path, *rt, sigma=2e-5, skip_bad=True)  # a comment on line 1
    assert list(meas.line) == [3, 7]
    q5, again, unknown = meas.dropped
    assert "line 4, column 'q5' (6): pose 'p1' has q5 = 31 here but 30 on line 3" in q5
    assert ("line 5, column 'marker' (8): marker 'A' is read twice in pose 'p1' under the same "
            "load (first on line 3)") in again
    assert "line 6, column 'marker' (8): marker 'Z' is not in the tool" in unknown
    with pytest.raises(DataError, match=r"line 4, column 'q5' \(6\)"):
        read_measurements(path, *rt, sigma=2e-5)
