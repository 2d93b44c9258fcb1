"""The command line end to end, through the user's files."""
import json

import numpy as np
import pytest

from doe_calib import IdentificationResult, examples
from doe_calib.cli import main


@pytest.fixture(scope="module")
def campaign(tmp_path_factory):
    d = tmp_path_factory.mktemp("campaign")
    common = ["--robot", examples.ROBOT_URDF, "--tool", examples.TOOL_YAML,
              "--model", "joint_offset+geometry+joint_compliance", "--load", "250@0,0,200",
              "--sigma", "0.02", "--tracker", "2500,-800,300,0,0,120"]
    assert main(["simulate", *common, "--poses", "40", "--seed", "1", "--out",
                 str(d / "train.csv"), "--truth-out", str(d / "truth.json")]) == 0
    assert main(["simulate", *common, "--poses", "15", "--seed", "2", "--truth",
                 str(d / "truth.json"), "--out", str(d / "valid.csv")]) == 0
    return d


@pytest.fixture(scope="module")
def identified(campaign):
    out = campaign / "result.json"
    assert main(["identify", "--robot", examples.ROBOT_URDF, "--tool", examples.TOOL_YAML,
                 "--data", str(campaign / "train.csv"), "--sigma", "0.02", "--out",
                 str(out)]) == 0
    return out


def test_identify_then_predict_held_out(campaign, identified, capsys):
    out = identified
    res = IdentificationResult.from_json(out)
    assert res.sigma_ratio == pytest.approx(1.0, abs=0.1)
    assert "dq_a2" in res.summary()
    pred = campaign / "pred.csv"
    capsys.readouterr()
    assert main(["predict", "--result", str(out), "--data", str(campaign / "valid.csv"),
                 "--out", str(pred)]) == 0
    line = capsys.readouterr().out
    rms = float(line.split("RMS ")[1].split(" mm")[0])
    assert rms < 1.2 * 0.02  # held-out error at the noise floor


def test_identify_reports_bad_input_and_exits_2(campaign, tmp_path, capsys):
    bad = tmp_path / "bad.csv"
    lines = (campaign / "train.csv").read_text().splitlines()
    header_at = next(i for i, ln in enumerate(lines) if not ln.startswith("#"))
    cols = lines[header_at].split(",")
    row = lines[header_at + 1].split(",")
    row[cols.index("x")] = "abc"
    lines[header_at + 1] = ",".join(row)
    bad.write_text("\n".join(lines) + "\n")
    code = main(["identify", "--robot", examples.ROBOT_URDF, "--tool", examples.TOOL_YAML,
                 "--data", str(bad), "--sigma", "0.02", "--out", str(tmp_path / "r.json")])
    err = capsys.readouterr().err
    assert code == 2
    assert f"line {header_at + 2}" in err and "x" in err and "bad.csv" in err


def test_pose_and_two_step_estimators_from_cli(campaign, tmp_path):
    for est in ("two-step", "pose"):
        out = tmp_path / f"{est}.json"
        assert main(["identify", "--robot", examples.ROBOT_URDF, "--tool", examples.TOOL_YAML,
                     "--data", str(campaign / "train.csv"), "--sigma", "0.02",
                     "--model", "joint_offset", "--estimator", est, "--out", str(out)]) == 0
        assert json.loads(out.read_text())["estimator"] == est


def test_simulated_truth_is_recovered_within_uncertainty(campaign, identified):
    truth = json.loads((campaign / "truth.json").read_text())["parameters"]
    res = IdentificationResult.from_json(identified)
    by_name = {r["name"]: r["value"] for r in truth}
    rows = {r["name"]: r for r in res.to_dict()["parameters"]}
    z = [(rows[n]["value"] - by_name[n]) / rows[n]["std"] for n in rows
         if rows[n]["free"] and rows[n]["std"] > 0 and rows[n]["block"] == "joint_compliance"]
    assert z and np.all(np.abs(z) < 5)
