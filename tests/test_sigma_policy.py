"""One σ policy (estimation/sigma.py): the Python API and the command line agree on σ-less data."""
import csv
import json
from dataclasses import replace
from pathlib import Path

import numpy as np
import pytest

import doe_calib
from doe_calib import Configurations, simulate
from doe_calib.cli import main
from doe_calib.diagnosis import diagnose
from doe_calib.estimation.identify import FitSettings, identify_quietly
from doe_calib.estimation.sigma import resolve_sigma
from doe_calib.io.csv_files import read_measurements, write_measurements
from doe_calib.io.measurements import concatenate
from doe_calib.model.simulate import random_configurations

DATA = Path(doe_calib.__file__).parent / "examples"
URDF, TOOL = DATA / "three_dof.urdf", DATA / "three_dof_tool.yaml"
SIGMA_MM = 0.02  # the true simulated σ


@pytest.fixture(scope="module")
def files(tmp_path_factory, model3):
    """The same simulated readings with and without a sigma column."""
    p = model3.nominal()
    v = p.values.copy()
    v[p.index(["dq_q1", "dq_q2", "dq_q3"])] = [1e-3, -2e-3, 1.5e-3]
    v[p.index("base")] = [1.5, -0.5, 0.2, 0.1, -0.2, 0.3]
    rng = np.random.default_rng(21)
    cfg = Configurations.from_arrays(random_configurations(model3.robot, 50, rng))
    d = tmp_path_factory.mktemp("policy")
    write_measurements(d / "with.csv", simulate(model3, v, cfg, SIGMA_MM / 1000, rng),
                       model3.robot, model3.tool)
    rows = list(csv.reader(ln for ln in (d / "with.csv").read_text().splitlines()
                           if not ln.startswith("#")))
    keep = [i for i, c in enumerate(rows[0]) if c != "sigma"]
    (d / "without.csv").write_text("\n".join(",".join(r[i] for i in keep) for r in rows) + "\n")
    return d / "with.csv", d / "without.csv"


def _cli(capsys, *args):
    capsys.readouterr()
    assert main(list(args)) == 0
    return json.loads(capsys.readouterr().out)


def test_python_and_cli_diagnose_agree_on_a_file_without_sigma(model3, files, tmp_path, capsys):
    without = files[1]
    py = diagnose(model3, read_measurements(without, model3.robot, model3.tool))
    cli = _cli(capsys, "diagnose", "--robot", str(URDF), "--tool", str(TOOL), "--data",
               str(without), "--model", "joint_offset", "--out", str(tmp_path / "d.json"),
               "--json")
    assert py.chi2["sigma_ratio"] == pytest.approx(cli["chi2"]["sigma_ratio"], rel=1e-9)
    assert py.chi2["sigma_ratio"] == pytest.approx(1.0, abs=0.05)  # tested at σ̂, not 1 mm
    assert py.noise_floor_mm == pytest.approx(SIGMA_MM, rel=0.1)  # σ̂ is the true σ
    assert py.verdict == cli["verdict"] and py.adequate == cli["adequate"]
    assert py.chi2["sigma_source"] == cli["chi2"]["sigma_source"] == "estimated"


def test_python_and_cli_identify_agree_on_a_file_without_sigma(model3, files, tmp_path, capsys):
    without = files[1]
    py = identify_quietly(model3, read_measurements(without, model3.robot, model3.tool))
    cli = _cli(capsys, "identify", "--robot", str(URDF), "--tool", str(TOOL), "--data",
               str(without), "--model", "joint_offset", "--out", str(tmp_path / "r.json"),
               "--json")
    assert py.sigma_mm == pytest.approx(cli["sigma_mm"], rel=1e-9)
    assert py.sigma_mm == pytest.approx(SIGMA_MM, rel=0.1)


def test_the_three_sources(model3, files):
    with_, without = files
    per = resolve_sigma(model3, read_measurements(with_, model3.robot, model3.tool))
    assert per.source == "per reading" and per.sigma_mm == pytest.approx(SIGMA_MM)
    assert "sigma column" in per.words
    given = resolve_sigma(model3, read_measurements(without, model3.robot, model3.tool,
                                                    sigma=5e-5))
    assert given.source == "given" and given.words == "σ given: 0.05 mm"
    assert resolve_sigma(model3, per.measurements, sigma=7e-5).measurements.sigma.max() == \
        pytest.approx(7e-5)
    raw = read_measurements(without, model3.robot, model3.tool)
    assert raw.sigma_estimated and raw.sigma_source == "estimated"
    est = resolve_sigma(model3, raw)
    assert est.source == "estimated" and not est.measurements.sigma_estimated
    assert est.sigma_mm == pytest.approx(SIGMA_MM, rel=0.1)
    assert np.allclose(est.measurements.sigma, est.sigma_mm / 1000)
    assert est.words.startswith("σ not given: estimated from the residuals of the starting model")
    # a fit of the σ-less readings at hand gives the same σ̂ without a second fit
    fit = identify_quietly(model3, raw)
    assert resolve_sigma(model3, raw, fit=fit).sigma_mm == fit.sigma_mm
    assert fit.sigma_mm == pytest.approx(est.sigma_mm, rel=1e-9)
    # settled readings stay settled; identify's own fit is left to estimate
    assert resolve_sigma(model3, est.measurements).measurements is est.measurements
    assert resolve_sigma(model3, raw, in_fit=True).measurements is raw


def test_sources_survive_subset_concatenate_and_replace(model3, files):
    with_, without = files
    per = read_measurements(with_, model3.robot, model3.tool)
    raw = read_measurements(without, model3.robot, model3.tool)
    given = read_measurements(without, model3.robot, model3.tool, sigma=3e-5)
    assert per.subset(np.arange(10)).sigma_source == "per reading"
    assert raw.subset(np.arange(10)).sigma_estimated
    assert concatenate([per, given]).sigma_source == "per reading"
    assert concatenate([given, given]).sigma_source == "given"
    both = concatenate([given, raw])
    assert both.sigma_source == "estimated" and both.sigma_estimated
    assert replace(per, sigma_estimated=True).sigma_source == "estimated"  # the old way
    with pytest.raises(ValueError, match="sigma_source"):
        replace(per, sigma_source="guessed")


def test_the_result_says_where_sigma_came_from(model3, files):
    with_sigma, without = files
    robot, tool = model3.robot, model3.tool
    cases = [(read_measurements(with_sigma, robot, tool), "per reading"),
             (read_measurements(without, robot, tool, sigma=5e-5), "given"),
             (read_measurements(without, robot, tool), "estimated")]
    for meas, source in cases:
        fit = identify_quietly(model3, meas)
        assert fit.sigma_source == source
        assert fit.fit_statistics.sigma_source == source
        assert fit.fit_statistics.chi2_informative == (source != "estimated")
    # σ estimated: σ̂ near the simulated σ; σ given 2.5× too large: σ̂/σ near 0.4
    assert identify_quietly(model3, cases[2][0]).sigma_mm == pytest.approx(SIGMA_MM, rel=0.15)
    assert identify_quietly(model3, cases[1][0]).sigma_ratio == pytest.approx(0.4, rel=0.15)


def test_the_reader_makes_no_sigma_up(model3, files):
    """Readings without σ come back as not given (NaN); a σ given or a sigma column is kept."""
    with_, without = files
    robot, tool = model3.robot, model3.tool
    raw = read_measurements(without, robot, tool)
    assert np.isnan(raw.sigma).all() and raw.sigma_estimated and raw.sigma_source == "estimated"
    given = read_measurements(without, robot, tool, sigma=5e-5)
    assert np.all(given.sigma == 5e-5) and given.sigma_source == "given"
    per = read_measurements(with_, robot, tool, sigma=5e-5)  # the column wins, reading by reading
    assert np.allclose(per.sigma, SIGMA_MM / 1000) and per.sigma_source == "per reading"


def test_one_function_decides_given_per_reading_or_estimated(model3, files):
    with_, without = files
    robot, tool = model3.robot, model3.tool
    raw = read_measurements(without, robot, tool)
    given = resolve_sigma(model3, raw, sigma=5e-5)
    assert given.source == "given" and np.all(given.measurements.sigma == 5e-5)
    per = resolve_sigma(model3, read_measurements(with_, robot, tool))
    assert per.source == "per reading" and np.allclose(per.measurements.sigma, 2e-5)
    est = resolve_sigma(model3, raw)
    assert est.source == "estimated" and np.all(np.isfinite(est.measurements.sigma))
    assert est.measurements.sigma[0] == pytest.approx(SIGMA_MM / 1000, rel=0.1)


def test_sigma_in_mm_on_the_command_line_and_in_metres_in_python_agree(model3, files, tmp_path,
                                                                        capsys):
    without = files[1]
    cli = _cli(capsys, "identify", "--robot", str(URDF), "--tool", str(TOOL), "--data",
               str(without), "--model", "joint_offset", "--sigma", "0.02", "--out",
               str(tmp_path / "r.json"), "--json")
    py = identify_quietly(model3, read_measurements(without, model3.robot, model3.tool),
                          sigma=2e-5, settings=FitSettings(select="cv")).to_dict()
    assert cli["sigma_mm"] == py["sigma_mm"] == 0.02 and cli["sigma_source"] == "given"
    assert [p["value"] for p in cli["parameters"]] == [p["value"] for p in py["parameters"]]
    assert cli["sigma_ratio"] == py["sigma_ratio"]
