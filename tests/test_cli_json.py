"""``--json``: every command that prints a table prints one JSON document and nothing else."""
import json
import sys
import types
from pathlib import Path

import pytest

from doe_calib import examples
from doe_calib.cli import COMMANDS, build_parser, main
from doe_calib.cli import study as study_cli

ROBOT = ["--robot", examples.ROBOT_URDF, "--tool", examples.TOOL_YAML]
MODEL = ["--model", "joint_offset+joint_compliance"]


def _not_json(constant):
    raise ValueError(f"{constant} is not valid JSON")


def run_json(capsys, *argv):
    """Run ``doe-calib ARGV --json``; the whole stdout parsed as one strict JSON document."""
    capsys.readouterr()
    assert main([*argv, "--json"]) == 0
    out = capsys.readouterr().out
    return json.loads(out, parse_constant=_not_json)


@pytest.fixture(scope="module")
def files(tmp_path_factory):
    return tmp_path_factory.mktemp("json")


@pytest.fixture(scope="module")
def campaign(files):
    """A small simulated campaign (12 poses, unloaded and loaded) and its true parameters."""
    assert main(["simulate", *ROBOT, *MODEL, "--poses", "12", "--load", "250@0,0,200",
                 "--seed", "3", "--out", str(files / "meas.csv"), "--truth-out",
                 str(files / "truth.json")]) == 0
    return files / "meas.csv"


@pytest.fixture(scope="module")
def result(campaign, files):
    out = files / "result.json"
    assert main(["identify", *ROBOT, *MODEL, "--data", str(campaign), "--sigma", "0.02",
                 "--out", str(out)]) == 0
    return out


@pytest.fixture(scope="module")
def design(files):
    out = files / "design.json"
    assert main(["design", *ROBOT, *MODEL, "--poses", "6", "--load", "250@0,0,200",
                 "--candidates", "300", "--no-refine", "--seed", "1", "--out", str(out)]) == 0
    return out


def test_every_table_command_has_json():
    parser = build_parser()
    sub = next(a for a in parser._actions if a.dest == "command")
    for name in COMMANDS:
        if name != "demo":
            options = {o for a in sub.choices[name]._actions for o in a.option_strings}
            assert "--json" in options, name


def test_simulate(capsys, tmp_path):
    doc = run_json(capsys, "simulate", *ROBOT, *MODEL, "--poses", "3", "--load",
                   "250@0,0,200", "--seed", "1", "--out", str(tmp_path / "m.csv"))
    assert doc["configurations"] == 6 and doc["poses"] == 3
    assert doc["readings"] == 6 * 3 and doc["measurements"] == str(tmp_path / "m.csv")


def test_identify_and_predict(capsys, campaign, result, tmp_path):
    doc = run_json(capsys, "identify", *ROBOT, *MODEL, "--data", str(campaign), "--sigma",
                   "0.02", "--out", str(tmp_path / "r.json"))
    assert doc["format"] == "doe_calib.identification"
    doc = run_json(capsys, "predict", "--result", str(result), "--data", str(campaign),
                   "--out", str(tmp_path / "pred.csv"))
    assert doc["readings"] == 12 * 2 * 3
    assert 0 < doc["error"]["rms_mm"] < 0.05  # the fit's own data: about σ = 0.02 mm


def test_design_export_compare(capsys, design, tmp_path):
    doc = run_json(capsys, "design", *ROBOT, *MODEL, "--poses", "6", "--candidates", "200",
                   "--no-refine", "--seed", "2", "--out", str(tmp_path / "d.json"))
    assert doc["format"] == "doe_calib.design" and len(doc["predicted_std"]) > 0
    doc = run_json(capsys, "export", str(design), "--format", "csv", "--out",
                   str(tmp_path / "prog"))
    assert doc["poses"] == 6 and doc["measurements"] == 12
    assert all(Path(f).exists() for f in doc["files"])
    doc = run_json(capsys, "compare", str(design), str(tmp_path / "d.json"))
    assert doc["format"] == "doe_calib.comparison" and len(doc["sources"]) == 2


def test_diagnose_and_refine(capsys, campaign, tmp_path):
    doc = run_json(capsys, "diagnose", *ROBOT, "--model", "joint_offset", "--data",
                   str(campaign), "--sigma", "0.02", "--out", str(tmp_path / "d.json"))
    assert isinstance(doc, dict) and doc
    doc = run_json(capsys, "refine", *ROBOT, "--model", "joint_offset", "--data",
                   str(campaign), "--sigma", "0.02", "--max-steps", "1", "--out",
                   str(tmp_path / "r.json"))
    assert isinstance(doc, dict) and doc


@pytest.fixture
def fake_study(monkeypatch):
    """A study that prints a table and writes OUT/fake.json, as the real ones do."""
    module = types.ModuleType("fake_study")

    def study_main(argv):
        out = Path(argv[argv.index("--out") + 1])
        out.mkdir(parents=True, exist_ok=True)
        (out / "fake.json").write_text(json.dumps({"rows": [1, 2]}))
        print("| a | b |\n|---|---|\n| 1 | 2 |")

    module.main = study_main
    monkeypatch.setitem(sys.modules, "fake_study", module)
    monkeypatch.setattr(study_cli, "STUDIES", {**study_cli.STUDIES, "fake": "fake_study"})


def test_study(capsys, fake_study, tmp_path):
    capsys.readouterr()
    assert main(["study", "fake", "--out", str(tmp_path), "--json"]) == 0
    captured = capsys.readouterr()
    assert json.loads(captured.out) == {"rows": [1, 2]}
    assert "| a | b |" in captured.err  # the study's table went to stderr
