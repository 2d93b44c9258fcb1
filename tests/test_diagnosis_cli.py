"""diagnose and refine from the command line, on the files a user brings; noise from repeats."""
import json
from dataclasses import replace

import numpy as np
import pytest

from doe_calib import Configurations, build_model, examples, simulate
from doe_calib.cli import main
from doe_calib.diagnosis import diagnose
from doe_calib.estimation.repeatability import repeatability
from doe_calib.io.csv_files import write_measurements
from doe_calib.io.measurements import concatenate
from doe_calib.model.loads import unloaded_and_loaded
from doe_calib.model.simulate import random_configurations, random_truth


@pytest.fixture(scope="module")
def files(tmp_path_factory, robot6, tool6):
    """A campaign and a validation file with a hidden cyclic error of joint 3."""
    rng = np.random.default_rng(4)
    true = build_model(robot6, tool6, "joint_offset+joint_compliance+cyclic(j3)")
    truth = random_truth(true, rng)
    out = tmp_path_factory.mktemp("diag")
    for name, n in (("m.csv", 30), ("v.csv", 15)):
        cfg = unloaded_and_loaded(true, truth, random_configurations(robot6, n, rng), 250,
                                  (0, 0, 0.2))
        write_measurements(out / name, simulate(true, truth, cfg, 3e-5, rng), robot6, tool6)
    return out


def test_diagnose_command_writes_json_plot_and_report(files, capsys):
    out = files
    args = ["--robot", examples.ROBOT_URDF, "--tool", examples.TOOL_YAML, "--data",
            str(out / "m.csv"), "--sigma", "0.03", "--model", "joint_offset+joint_compliance"]
    assert main(["diagnose", *args, "--out", str(out / "d.json"), "--report",
                 str(out / "d.html")]) == 0
    d = json.loads((out / "d.json").read_text())
    assert {"model", "rms_mm", "noise_floor_mm", "adequate", "candidates"} <= set(d)
    top = d["candidates"][0]
    assert (top["effect"], top["joint"]) == ("cyclic", 3) and not d["adequate"]
    assert {"statistic", "p_value", "cv_rms_mm", "explained_fraction"} <= set(top)
    assert (out / "d_residuals.png").stat().st_size > 10_000
    assert "cyclic" in capsys.readouterr().out
    assert "data:image/png;base64," in (out / "d.html").read_text()


def test_refine_result_is_what_predict_takes(files):
    out = files
    assert main(["refine", "--robot", examples.ROBOT_URDF, "--tool", examples.TOOL_YAML,
                 "--data", str(out / "m.csv"), "--sigma", "0.03", "--model", "joint_offset",
                 "--validation", str(out / "v.csv"), "--out", str(out / "r.json"),
                 "--workers", "2"]) == 0
    steps = json.loads((out / "r_refine.json").read_text())["steps"]
    assert steps[-1]["adequate"] and steps[-1]["validation_rms_mm"] < 0.04
    assert main(["predict", "--result", str(out / "r.json"), "--data", str(out / "v.csv"),
                 "--out", str(out / "p.csv")]) == 0
    rows = [r for r in (out / "p.csv").read_text().splitlines() if r and r[0] != "#"]
    assert len(rows) == 1 + 15 * 2 * 3  # header, then every reading of the validation file


def test_workers_must_be_a_whole_number_of_threads(files, capsys):
    args = ["--robot", examples.ROBOT_URDF, "--tool", examples.TOOL_YAML, "--data",
            str(files / "m.csv"), "--sigma", "0.03", "--model", "joint_offset"]
    for bad in ("0", "two"):
        assert main(["diagnose", *args, "--out", str(files / "w.json"), "--workers", bad]) != 0
        assert "--workers" in (err := capsys.readouterr().err) and bad in err and "thread" in err
    assert not (files / "w.json").exists()


def test_repeated_readings_give_sigma_only_when_none_is_given(robot6, tool6):
    """Each configuration read three times: the pooled spread is the true σ. A σ claimed is
    the σ used, the spread reported beside it; without a σ, the spread is σ."""
    rng = np.random.default_rng(9)
    model = build_model(robot6, tool6, "joint_offset")
    truth = random_truth(model, rng)
    cfg = Configurations.from_arrays(random_configurations(robot6, 25, rng))
    reads = [simulate(model, truth, cfg, 5e-5, rng) for _ in range(3)]
    claimed = [replace(r, sigma=r.sigma * 0.2) for r in reads]  # σ = 0.01 mm claimed
    same = concatenate(claimed)
    assert repeatability(claimed[0]) is None
    rep = repeatability(same)
    assert rep.sigma_mm == pytest.approx(0.05, rel=0.1) and rep.dof == 3 * 2 * len(reads[0])
    d = diagnose(model, same)
    assert d.chi2["sigma_source"] == "given" and d.noise_floor_mm == pytest.approx(0.01)
    assert not d.adequate and d.chi2["sigma_ratio"] == pytest.approx(5.0, rel=0.1)
    assert d.chi2["repeated"]["sigma_mm"] == pytest.approx(rep.sigma_mm)
    assert f"σ of repeated readings {rep.sigma_mm:.4g} mm" in d.summary()
    unknown = replace(same, sigma_estimated=True)
    d = diagnose(model, unknown)
    assert d.chi2["sigma_source"] == "repeated readings" and d.adequate
    assert d.noise_floor_mm == pytest.approx(rep.sigma_mm)


def test_exclude_poses_is_reported_and_cv_by_region(files, capsys):
    out = files
    args = ["--robot", examples.ROBOT_URDF, "--tool", examples.TOOL_YAML, "--data",
            str(out / "m.csv"), "--sigma", "0.03", "--model", "joint_offset+joint_compliance"]
    assert main(["diagnose", *args, "--exclude-poses", "1,2", "--cv-by", "region",
                 "--out", str(out / "x.json")]) == 0
    err = capsys.readouterr().err
    assert "excluded at your request: pose 1 (6 readings, lines" in err
    assert "excluded at your request: pose 2 (6 readings" in err
    d = json.loads((out / "x.json").read_text())
    assert "regions of joint space" in d["cv_grouping"]
    assert d["n_observations"] == 3 * (6 * 30 - 12)
    assert main(["diagnose", *args, "--exclude-poses", "nope", "--out",
                 str(out / "y.json")]) == 2
    assert "--exclude-poses: no pose 'nope'" in capsys.readouterr().err
