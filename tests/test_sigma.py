"""σ: estimated from the residuals when not given, stored in designs, propagated by predict."""
import csv
import json
from pathlib import Path

import numpy as np
import pytest

import doe_calib
from doe_calib import Configurations, IdentificationResult, simulate
from doe_calib.cli import main
from doe_calib.design.comparison import compare
from doe_calib.design.optimal import optimal_design
from doe_calib.design.result import DesignResult
from doe_calib.estimation.predict import predict
from doe_calib.estimation.identify import identify_quietly
from doe_calib.io.csv_files import read_measurements, write_measurements
from doe_calib.model.simulate import random_configurations

DATA = Path(doe_calib.__file__).parent / "examples"
URDF, TOOL = DATA / "three_dof.urdf", DATA / "three_dof_tool.yaml"
SIGMA = 2e-5  # m: the true simulated σ


@pytest.fixture(scope="module")
def truth(model3):
    p = model3.nominal()
    v = p.values.copy()
    v[p.index(["dq_q1", "dq_q2", "dq_q3"])] = [1e-3, -2e-3, 1.5e-3]
    v[p.index("base")] = [1.5, -0.5, 0.2, 0.1, -0.2, 0.3]
    return v


def _without_sigma_column(src, dst):
    rows = [r for r in csv.reader(line for line in Path(src).read_text().splitlines()
                                  if not line.startswith("#"))]
    keep = [i for i, c in enumerate(rows[0]) if c != "sigma"]
    Path(dst).write_text("\n".join(",".join(r[i] for i in keep) for r in rows) + "\n")
    return dst


@pytest.fixture(scope="module")
def no_sigma_file(tmp_path_factory, model3, truth):
    rng = np.random.default_rng(7)
    cfg = Configurations.from_arrays(random_configurations(model3.robot, 60, rng))
    meas = simulate(model3, truth, cfg, SIGMA, rng)
    d = tmp_path_factory.mktemp("sigma")
    write_measurements(d / "with.csv", meas, model3.robot, model3.tool)
    return _without_sigma_column(d / "with.csv", d / "without.csv")


def test_sigma_estimated_from_the_residuals_when_not_given(model3, no_sigma_file):
    meas = read_measurements(no_sigma_file, model3.robot, model3.tool)
    assert meas.sigma_estimated
    res = identify_quietly(model3, meas)
    assert res.sigma_estimated and res.sigma_ratio == 1.0
    assert res.sigma_mm == pytest.approx(SIGMA * 1000.0, rel=0.10)
    # the covariance is the one for σ = σ̂: the same as with σ̂ given
    given = identify_quietly(model3, read_measurements(no_sigma_file, model3.robot, model3.tool,
                                                       sigma=res.sigma_mm / 1000))
    assert np.allclose(res.std(apriori=True), given.std(apriori=True), rtol=1e-6)
    assert not given.sigma_estimated
    words = f"σ estimated from the residuals: {res.sigma_mm:.3g} mm"
    assert words in res.warnings and "σ estimated from the residuals" in res.summary()
    again = IdentificationResult.from_dict(json.loads(res.to_json()))
    assert again.sigma_estimated and again.sigma_mm == res.sigma_mm


def test_identify_cli_without_sigma_says_so(no_sigma_file, tmp_path, capsys):
    out = tmp_path / "r.json"
    assert main(["identify", "--robot", str(URDF), "--tool", str(TOOL), "--data",
                 str(no_sigma_file), "--model", "joint_offset", "--out", str(out)]) == 0
    assert "σ estimated from the residuals" in capsys.readouterr().out
    d = json.loads(out.read_text())
    assert d["sigma_estimated"] is True
    assert d["sigma_mm"] == pytest.approx(SIGMA * 1000.0, rel=0.10)


def test_diagnose_cli_without_sigma_uses_the_estimate(no_sigma_file, tmp_path, capsys):
    out = tmp_path / "d.json"
    assert main(["diagnose", "--robot", str(URDF), "--tool", str(TOOL), "--data",
                 str(no_sigma_file), "--model", "joint_offset", "--out", str(out)]) == 0
    err = capsys.readouterr().err
    line = next(ln for ln in err.splitlines() if ln.startswith("σ not given"))
    assert "estimated from the residuals of the starting model" in line
    assert float(line.split(", ")[-1].split(" mm")[0]) == pytest.approx(SIGMA * 1000, rel=0.10)


def test_refine_cli_without_sigma_validates_at_the_estimate(no_sigma_file, tmp_path, capsys):
    out = tmp_path / "r.json"
    assert main(["refine", "--robot", str(URDF), "--tool", str(TOOL), "--data",
                 str(no_sigma_file), "--validation", str(no_sigma_file), "--model",
                 "joint_offset", "--max-steps", "1", "--out", str(out)]) == 0
    err = capsys.readouterr().err
    line = next(ln for ln in err.splitlines() if ln.startswith("σ not given"))
    sigma_hat = float(line.split(", ")[-1].split(" mm")[0])
    assert sigma_hat == pytest.approx(SIGMA * 1000, rel=0.10)
    fit = IdentificationResult.from_json(out)
    assert not fit.sigma_estimated and fit.sigma_mm == pytest.approx(sigma_hat, rel=1e-2)
    assert fit.sigma_ratio == pytest.approx(1.0, abs=0.02)  # the data fitted at their own σ̂


def test_design_stores_its_sigma_and_compare_uses_it(model3, tmp_path):
    design = optimal_design(model3, 8, candidates=300, sigma=3e-5, refine=False,
                            rng=np.random.default_rng(1))
    assert design.to_dict()["sigma_mm"] == pytest.approx(0.03)
    design.to_json(tmp_path / "d.json")
    back = DesignResult.from_json(tmp_path / "d.json")
    assert back.sigma_mm == pytest.approx(0.03)
    table = compare([back])
    assert table.sigma_mm[0] == pytest.approx(0.03)
    std = dict(zip(table.names, table.std[:, 0]))
    assert len(design.predicted_std) >= 6  # base and markers at least
    for name, (s, _) in design.predicted_std.items():
        assert std[name] == pytest.approx(s, rel=1e-6)
    # a design file from before σ was stored still compares at the old default
    old = back.to_dict()
    del old["sigma_mm"]
    assert compare([DesignResult.from_dict(old)]).sigma_mm[0] == pytest.approx(0.02)


def test_predicted_std_matches_a_monte_carlo_of_identifications(model3, truth):
    rng = np.random.default_rng(11)
    cfg = Configurations.from_arrays(random_configurations(model3.robot, 12, rng))
    held = Configurations.from_arrays(random_configurations(model3.robot, 5, rng))
    probe = simulate(model3, truth, held, SIGMA, rng)  # poses to predict
    fits = [identify_quietly(model3, simulate(model3, truth, cfg, SIGMA, rng))
            for _ in range(300)]
    predicted = np.array([predict(f, probe, model3, apriori=True).xyz for f in fits])
    empirical = predicted.std(axis=0, ddof=1)  # (K, 3)
    std = predict(fits[0], probe, model3, apriori=True).std
    assert std.min() > 1e-6  # nonzero: tens of µm, like σ
    ratio = empirical / std
    assert np.all((ratio > 0.8) & (ratio < 1.2)), ratio


def test_predict_writes_std_columns_that_read_back(model3, truth, tmp_path, no_sigma_file):
    meas = read_measurements(no_sigma_file, model3.robot, model3.tool, sigma=2e-5)
    res = identify_quietly(model3, meas)
    res.to_json(tmp_path / "r.json")
    pred = tmp_path / "p.csv"
    assert main(["predict", "--result", str(tmp_path / "r.json"), "--data", str(no_sigma_file),
                 "--out", str(pred)]) == 0
    rows = list(csv.DictReader(ln for ln in pred.read_text().splitlines()
                               if not ln.startswith("#")))
    got = np.array([[float(r[c]) for c in ("std_x", "std_y", "std_z")] for r in rows])
    want = predict(res, meas, model3, apriori=True).std
    assert np.allclose(got, want * 1000.0, rtol=1e-9)
    assert np.allclose([float(r["sigma"]) for r in rows], 0.02)
    back = read_measurements(pred, model3.robot, model3.tool)  # std columns ignored
    assert len(back) == len(meas) and not back.sigma_estimated
    assert np.allclose(back.xyz, predict(res, meas, model3, apriori=True).xyz, atol=1e-9)


def test_simulated_data_without_sigma_and_a_sigma_given_disagree_by_the_ratio(
        model3, no_sigma_file):
    """A σ given 2× too large: σ̂/σ ≈ 0.5, while the estimate is the true σ."""
    meas = read_measurements(no_sigma_file, model3.robot, model3.tool, sigma=4e-5)
    res = identify_quietly(model3, meas)
    assert res.sigma_ratio == pytest.approx(0.5, rel=0.10)


def test_refine_without_sigma_names_its_line_the_starting_models_estimate(no_sigma_file,
                                                                           tmp_path, capsys):
    out = tmp_path / "r.json"
    assert main(["refine", "--robot", str(URDF), "--tool", str(TOOL), "--data",
                 str(no_sigma_file), "--model", "joint_offset", "--max-steps", "1",
                 "--out", str(out)]) == 0
    said = capsys.readouterr()
    line = next(ln for ln in said.out.splitlines() if ln.startswith("(mm per coordinate"))
    sigma_hat = float(next(ln for ln in said.err.splitlines() if ln.startswith("σ not given"))
                      .split(", ")[-1].split(" mm")[0])
    assert "σ̂ of the starting model's fit (no σ given)" in line and "noise floor" not in line
    assert float(line.split()[-2]) == pytest.approx(sigma_hat, rel=1e-2)
    given = tmp_path / "g.json"
    assert main(["refine", "--robot", str(URDF), "--tool", str(TOOL), "--data",
                 str(no_sigma_file), "--sigma", str(SIGMA * 1000), "--model", "joint_offset",
                 "--max-steps", "1", "--out", str(given)]) == 0
    assert f"noise floor {SIGMA * 1000:.4f} mm" in capsys.readouterr().out
