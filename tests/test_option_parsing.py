"""Any text given to an option or in a CSV file gives a value or a DoeCalibError, never a crash."""
import math

import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from doe_calib.cli.common import MAX_LOAD_KG, model_option, parse_floats, parse_load
from doe_calib.cli.options import at_least, count, fraction, positive, probability
from doe_calib.errors import DataError, DoeCalibError
from doe_calib.io.table import read_table
from doe_calib.model.effects import parse_model

QUICK = settings(max_examples=300, deadline=None,
                 suppress_health_check=[HealthCheck.function_scoped_fixture])
NUMBERISH = st.text(alphabet="0123456789.,@:-+eE naif;()=_jqx", max_size=30)
ANY_TEXT = st.one_of(st.text(max_size=40), NUMBERISH)


@QUICK
@given(ANY_TEXT)
def test_parse_load(text):
    try:
        kg, com, radius = parse_load(text)
    except DoeCalibError:
        return
    assert 0.0 <= kg <= MAX_LOAD_KG and com.shape == (3,) and (radius is None or radius > 0)


@QUICK
@given(ANY_TEXT, st.integers(1, 6))
def test_parse_floats(text, n):
    try:
        values = parse_floats(text, n, "--task-point")
    except DoeCalibError as exc:
        assert "--task-point" in str(exc)
        return
    assert values.shape == (n,) and all(math.isfinite(v) for v in values)


@QUICK
@given(ANY_TEXT)
def test_number_options(text):
    for convert, ok in ((positive("--sigma", "mm"), lambda v: v > 0),
                        (at_least("--dwell", 0.0, "s"), lambda v: v >= 0),
                        (count("--poses", 1), lambda v: isinstance(v, int) and v >= 1),
                        (probability("--level"), lambda v: 0 < v < 1),
                        (fraction("--min-gain"), lambda v: 0 <= v < 1)):
        try:
            value = convert(text)
        except DoeCalibError as exc:
            assert str(exc).startswith("--")
            continue
        assert math.isfinite(value) and ok(value)


@QUICK
@given(st.one_of(st.text(max_size=40),
                 st.lists(st.sampled_from(["joint_offset", "geometry", "cyclic(j3)",
                                           "cyclic(a3)", "backlash(j2,mode=torque)",
                                           "thermal(t_ref=x)", "compliance_by_angle(j2,bins=0)",
                                           "gear_ratio(", "+", "(", ")", "none", " "]),
                          max_size=5).map("".join)))
def test_model_strings(text):
    try:
        spec = model_option(text)
        effects = parse_model(spec)
    except DoeCalibError:
        return
    assert all(e.name for e in effects)


FIELDS = st.lists(st.sampled_from(["pose", "q1", "x", "1,5", "2.5", "", '"a', "é", "\x00",
                                   " # c"]), max_size=6)
ROW = st.one_of(st.text(max_size=30),
                st.tuples(st.sampled_from([",", ";", "\t"]), FIELDS).map(lambda t: t[0].join(t[1])))
LINES = st.lists(ROW, max_size=6)


@QUICK
@given(LINES, st.sampled_from(["utf-8", "latin-1"]), st.binary(max_size=20))
def testread_table(tmp_path, lines, encoding, tail):
    path = tmp_path / "t.csv"
    path.write_bytes("\n".join(lines).encode(encoding, errors="replace") + tail)
    try:
        table = read_table(path)
    except DataError:
        return
    assert table.columns and table.rows
    assert all(isinstance(line, int) and line >= 1 for line, _ in table.rows)


def test_read_table_semicolons_with_decimal_commas(tmp_path):
    path = tmp_path / "t.csv"
    path.write_text("# exported by a spreadsheet\npose;x\n1;2,5\n", encoding="utf-8")
    table = read_table(path)
    assert table.columns == ["pose", "x"] and table.rows == [(3, ["1", "2,5"])]
    assert table.decimal_comma


def test_read_table_reports_the_first_bad_byte(tmp_path):
    path = tmp_path / "t.csv"
    path.write_bytes("pose,x\n1,2\nGrüße,3\n".encode("latin-1"))
    with pytest.raises(DataError, match=r"t.csv, line 3, column 3: byte 0xfc is not UTF-8"):
        read_table(path)
