"""Every user mistake ends in one line naming the option, file, line or column, exit status 2."""
import json

import pytest

from doe_calib import examples
from doe_calib.cli import main

ROBOT = ["--robot", examples.ROBOT_URDF, "--tool", examples.TOOL_YAML]


@pytest.fixture(scope="module")
def files(tmp_path_factory):
    """A small simulated campaign and a small design, written by the commands themselves."""
    d = tmp_path_factory.mktemp("errors")
    assert _run(["simulate", *ROBOT, "--model", "joint_offset", "--poses", "8", "--seed", "1",
                 "--out", str(d / "m.csv")]) == 0
    assert _run(["design", *ROBOT, "--model", "joint_offset", "--poses", "6", "--candidates",
                 "200", "--no-refine", "--seed", "1", "--out", str(d / "d.json")]) == 0
    return d


def _run(argv) -> int:
    return main([str(a) for a in argv])


def _fails(capsys, argv, *words):
    """Run the command line; it must exit 2 with one ``error:`` line holding ``words``."""
    capsys.readouterr()
    code = _run(argv)
    err = capsys.readouterr().err
    assert code == 2, err
    assert "Traceback" not in err
    line = err.strip().splitlines()[-1]
    assert line.startswith("error: "), err
    for w in words:
        assert w in line, line
    return line


def test_fix_and_free_unknown_names_list_close_ones(files, tmp_path, capsys):
    common = ["identify", *ROBOT, "--data", files / "m.csv", "--model", "joint_offset",
              "--sigma", "0.02", "--out", tmp_path / "r.json"]
    _fails(capsys, [*common, "--fix", "dq_a9"], "--fix", "'dq_a9'", "dq_a6")
    _fails(capsys, [*common, "--free", "joint_ofset"], "--free", "joint_offset")
    _fails(capsys, [*common, "--fix", "dq_a1,,dq_a2"], "--fix", "empty name")
    assert not (tmp_path / "r.json").exists()


@pytest.mark.parametrize("poses", ["0", "1", "-3", "2"])
def test_design_refuses_too_few_poses(poses, tmp_path, capsys):
    line = _fails(capsys, ["design", *ROBOT, "--poses", poses, "--candidates", "200",
                           "--no-refine", "--out", tmp_path / "d.json"], "--poses")
    if int(poses) > 0:
        assert "identifiable parameters" in line and "at least" in line and "by counting" in line
    assert not (tmp_path / "d.json").exists()


@pytest.mark.parametrize("poses", ["0", "-2", "x"])
def test_simulate_refuses_no_poses(poses, tmp_path, capsys):
    _fails(capsys, ["simulate", *ROBOT, "--poses", poses, "--out", tmp_path / "m.csv"],
           "--poses")


@pytest.mark.parametrize("option, value", [
    ("--out", "missing/r.json"), ("--report", "missing/r.html"), ("--out", "m.csv/r.json"),
    ("--out", "."), ("--report", "r.json")])
def test_identify_checks_outputs_first(files, option, value, tmp_path, capsys, monkeypatch):
    monkeypatch.chdir(files)
    argv = ["identify", *ROBOT, "--data", "m.csv", "--sigma", "0.02", "--out", "r.json",
            option, value]
    _fails(capsys, argv, option, value)
    assert not (files / "r.json").exists()


@pytest.mark.parametrize("command, option", [
    (["simulate", *ROBOT, "--out", "m.csv"], "--out"),
    (["simulate", *ROBOT, "--out", "ok.csv"], "--truth-out"),
    (["design", *ROBOT, "--out", "d.json"], "--report"),
    (["predict", "--result", "r.json", "--data", "m.csv", "--out", "p.csv"], "--out"),
    (["diagnose", *ROBOT, "--data", "m.csv", "--out", "x.json"], "--plot"),
    (["refine", *ROBOT, "--data", "m.csv", "--out", "x.json"], "--history"),
    (["compare", "d.json", "--sigma", "0.02"], "--plot"),
    (["export", "d.json", "--format", "krl"], "--out"),
    (["demo"], "--out"),
    (["study", "table1"], "--out")])
def test_every_writing_command_checks_its_outputs(command, option, tmp_path, capsys,
                                                  monkeypatch):
    """Into a folder under a plain file: refused before reading any input."""
    monkeypatch.chdir(tmp_path)
    (tmp_path / "file").write_text("not a folder")
    argv = list(command)
    if option in argv:
        del argv[argv.index(option):argv.index(option) + 2]
    _fails(capsys, [*argv, option, "file/sub/x.out"], option, "file")


def test_design_out_must_be_json(tmp_path, capsys):
    _fails(capsys, ["design", *ROBOT, "--out", tmp_path / "x.csv"], "--out", ".json",
           "x.json")
    assert not (tmp_path / "x.csv").exists()


def test_simulate_takes_the_design_json_and_its_csv(files, tmp_path, capsys):
    for name in ("d.json", "d.csv"):
        out = tmp_path / f"from_{name}.csv"
        assert _run(["simulate", *ROBOT, "--model", "joint_offset", "--design", files / name,
                     "--seed", "2", "--out", out]) == 0
    assert (tmp_path / "from_d.json.csv").read_text().splitlines()[1:] == \
        (tmp_path / "from_d.csv.csv").read_text().splitlines()[1:]


def test_simulate_design_and_load_are_exclusive(files, tmp_path, capsys):
    _fails(capsys, ["simulate", *ROBOT, "--design", files / "d.json", "--load", "250@0,0,0",
                    "--out", tmp_path / "m.csv"], "--load", "--design")


def test_zero_load_writes_a_file_identify_accepts(tmp_path):
    data = tmp_path / "m.csv"
    assert _run(["simulate", *ROBOT, "--model", "joint_offset", "--poses", "8",
                 "--load", "0@0,0,200", "--seed", "3", "--out", data]) == 0
    assert _run(["identify", *ROBOT, "--model", "joint_offset", "--data", data,
                 "--out", tmp_path / "r.json"]) == 0


@pytest.mark.parametrize("argv", [
    ["simulate", *ROBOT, "--sigma", "-1", "--out", "m.csv"],
    ["simulate", *ROBOT, "--sigma", "0", "--out", "m.csv"],
    ["identify", *ROBOT, "--data", "m.csv", "--sigma", "-0.03", "--out", "r.json"],
    ["diagnose", *ROBOT, "--data", "m.csv", "--sigma", "nan", "--out", "x.json"],
    ["compare", "d.json", "--sigma", "0"],
    ["design", *ROBOT, "--sigma", "-0.02", "--out", "x.json"]])
def test_sigma_must_be_positive_and_names_the_option(files, argv, capsys, monkeypatch):
    monkeypatch.chdir(files)
    line = _fails(capsys, argv, "--sigma")
    assert "m.csv" not in line and "mm" in line


@pytest.mark.parametrize("load", ["-250@0,0,200", "1e9@0,0,200", "abc@0,0,0", "250@0,0",
                                  "nan@0,0,0"])
def test_absurd_loads(load, tmp_path, capsys):
    _fails(capsys, ["simulate", *ROBOT, f"--load={load}", "--out", tmp_path / "m.csv"],
           "--load")


@pytest.mark.parametrize("option, value", [("--handshake", "-1"), ("--handshake", "0"),
                                           ("--dwell", "-2")])
def test_export_settings(files, option, value, tmp_path, capsys):
    line = _fails(capsys, ["export", files / "d.json", "--format", "krl", "--out", tmp_path,
                           option, value], option)
    assert "d.json" not in line


def test_empty_model_needs_the_word_none(tmp_path, capsys):
    _fails(capsys, ["simulate", *ROBOT, "--model", "", "--out", tmp_path / "m.csv"],
           "--model", "none")
    assert _run(["simulate", *ROBOT, "--model", "none", "--poses", "5", "--json",
                 "--out", tmp_path / "m.csv"]) == 0
    assert json.loads(capsys.readouterr().out)["model"] == ""


def test_one_joint_named_two_ways(tmp_path, capsys):
    _fails(capsys, ["simulate", *ROBOT, "--model", "cyclic(j3)+cyclic(a3)",
                    "--out", tmp_path / "m.csv"], "cyclic(j3", "cyclic(a3", "cyc_a3_s1")


def test_identifiability_warning_is_one_sentence(tmp_path, capsys):
    data = tmp_path / "m.csv"
    assert _run(["simulate", *ROBOT, "--poses", "20", "--load", "250@0,0,200", "--seed", "4",
                 "--out", data]) == 0
    capsys.readouterr()
    assert _run(["identify", *ROBOT, "--data", data, "--out", tmp_path / "r.json"]) == 0
    warnings = [ln for ln in capsys.readouterr().err.splitlines() if ln.startswith("warning:")]
    fixed = next(w for w in warnings if "not separable" in w)
    assert len(fixed) < 300 and "geometry" in fixed and "--verbose" in fixed
    assert _run(["identify", *ROBOT, "--data", data, "--verbose",
                 "--out", tmp_path / "r.json"]) == 0
    listed = [ln for ln in capsys.readouterr().err.splitlines() if ln.startswith("fixed: ")]
    assert len(listed) == int(fixed.split()[1])


def test_help_points_to_the_formats(capsys):
    with pytest.raises(SystemExit):
        main(["identify", "--help"])
    out = capsys.readouterr().out
    assert "docs/formats.md" in out and "data" in out


def _rewrite(source, target, separator=",", decimal=".", encoding="utf-8", edit=None):
    """The measurement file ``source`` with other separators, decimal marks or encoding.

    ``edit(index, fields)`` may change the fields of the index-th line written;
    the comment lines (not ASCII) are left out of a file not in UTF-8.
    """
    lines = source.read_text(encoding="utf-8").splitlines()
    out = []
    for line in lines:
        if line.startswith("#"):
            if encoding == "utf-8":
                out.append(line)
            continue
        fields = line.split(",")
        if edit is not None:
            fields = edit(len(out), fields)
        out.append(separator.join(f.replace(".", decimal) for f in fields))
    target.write_bytes(("\n".join(out) + "\n").encode(encoding))
    return target


@pytest.mark.parametrize("separator, decimal", [(";", ","), (";", "."), ("\t", "."),
                                                ("\t", ",")])
def test_semicolon_and_tab_files_with_decimal_commas_are_read(files, tmp_path, separator,
                                                               decimal):
    data = _rewrite(files / "m.csv", tmp_path / "m.csv", separator, decimal)
    assert _run(["identify", *ROBOT, "--model", "joint_offset", "--data", data,
                 "--json", "--out", tmp_path / "r.json"]) == 0
    ref = tmp_path / "ref.json"
    assert _run(["identify", *ROBOT, "--model", "joint_offset", "--data", files / "m.csv",
                 "--out", ref]) == 0
    assert json.loads((tmp_path / "r.json").read_text())["parameters"] == \
        json.loads(ref.read_text())["parameters"]


def test_decimal_commas_in_a_comma_file_get_a_hint(files, tmp_path, capsys):
    data = _rewrite(files / "m.csv", tmp_path / "m.csv", ",", ",")
    _fails(capsys, ["identify", *ROBOT, "--data", data, "--out", tmp_path / "r.json"],
           "m.csv", "line 3", "fields where the header has", "decimal commas")


def test_latin1_file_names_line_and_column_of_the_bad_byte(files, tmp_path, capsys):
    def rename(row, fields):
        if row == 3:
            fields[0] = "Pose_é"
        return fields
    data = _rewrite(files / "m.csv", tmp_path / "m.csv", edit=rename, encoding="latin-1")
    _fails(capsys, ["identify", *ROBOT, "--data", data, "--out", tmp_path / "r.json"],
           "m.csv, line 4, column 6", "0xe9", "UTF-8")


def test_implausible_temperature_names_line_and_column(files, tmp_path, capsys):
    def hot(row, fields):
        return fields + (["temperature"] if row == 1 else ["2000" if row == 4 else "21.5"])
    data = _rewrite(files / "m.csv", tmp_path / "m.csv", edit=hot)
    _fails(capsys, ["identify", *ROBOT, "--data", data, "--out", tmp_path / "r.json"],
           "m.csv, line 5, column 'temperature'", "2000 °C", "-50 to 150 °C")


def test_compare_sigma_in_the_library_names_the_option_in_mm(files):
    from doe_calib.design.comparison import compare, load_source
    from doe_calib.errors import OptionError
    with pytest.raises(OptionError, match=r"--sigma\) must be positive, got 0 mm"):
        compare([load_source(files / "d.json")], ["d"], 0.0)


def test_formats_doc_names_every_key_the_commands_write(files, tmp_path):
    from pathlib import Path
    doc = (Path(__file__).parents[1] / "docs" / "formats.md").read_text(encoding="utf-8")
    result = tmp_path / "r.json"
    assert _run(["identify", *ROBOT, "--model", "joint_offset", "--data", files / "m.csv",
                 "--out", result]) == 0
    for path in (files / "d.json", result):
        data = json.loads(path.read_text())
        keys = set(data) | set(data["parameters" if "parameters" in data else "poses"][0])
        missing = [k for k in keys if f"`{k}`" not in doc and f"{k}`" not in doc]
        assert not missing, (path.name, missing)
    header = (files / "m.csv").read_text().splitlines()[1].split(",")
    assert all(f"`{c}`" in doc or c.rstrip("0123456789") in ("q", "approach") for c in header)



@pytest.mark.parametrize("option, argv", [
    ("--tracker", ["simulate", *ROBOT, "--tracker", "2500,0,nan,0,0,0", "--out", "m.csv"]),
    ("--tracker", ["simulate", *ROBOT, "--tracker", "1,2,3", "--out", "m.csv"]),
    ("--task-point", ["design", *ROBOT, "--model", "joint_offset", "--candidates", "200",
                      "--no-refine", "--task-point", "0,0", "--out", "d.json"])])
def test_vectors_must_be_finite_and_complete(option, argv, tmp_path, capsys, monkeypatch):
    monkeypatch.chdir(tmp_path)
    _fails(capsys, argv, option)
