"""Compare: more poses never predict worse, TCP std matches an independent computation, CLI."""
import warnings
from dataclasses import replace

import numpy as np
import pytest

from doe_calib import FitSettings, build_model, identify, simulate
from doe_calib.cli import main
from doe_calib.design import LoadCase, load_configurations
from doe_calib.design.comparison import compare, load_source
from doe_calib.design.optimal import optimal_design
from doe_calib.io.csv_files import write_design
from doe_calib.model.evaluation import evaluate, marker_positions
from doe_calib.model.simulate import random_configurations

SIGMA = 2e-5  # m
MODEL = "joint_offset+joint_compliance"
LOADS = [LoadCase(250.0, (0.0, 0.0, 0.2))]


@pytest.fixture(scope="module")
def model(robot6, tool6):
    return build_model(robot6, tool6, MODEL)


@pytest.fixture(scope="module")
def designs(model):
    """A 6-pose optimal design and the same 6 poses plus 6 more (12 poses)."""
    small = optimal_design(model, 6, LOADS, candidates=300, sigma=SIGMA, refine=False,
                           rng=np.random.default_rng(7))
    extra = random_configurations(model.robot, 6, np.random.default_rng(8))
    q = np.vstack([small.configurations.q[::2], extra])
    big = replace(small, configurations=load_configurations(model, model.nominal().values, q,
                                                            LOADS))
    return small, big


@pytest.fixture(scope="module")
def task(model):
    return load_configurations(model, model.nominal().values,
                               random_configurations(model.robot, 4, np.random.default_rng(9)),
                               LOADS)


def test_more_poses_never_predict_worse(designs):
    c = compare(designs, ["6", "12"], sigma=SIGMA)
    assert c.std.shape[1] == 2
    fixed = np.isnan(c.std[:, 0])
    assert np.array_equal(fixed, np.isnan(c.std[:, 1])) and (~fixed).sum() > 5
    assert np.all(c.std[~fixed, 1] <= c.std[~fixed, 0] * (1 + 1e-9))
    assert c.n_poses == (6, 12)


def test_design_std_is_the_designs_prediction(designs):
    small, _ = designs
    c = compare([small], sigma=SIGMA)
    for name, (std, unit) in small.predicted_std.items():
        i = c.names.index(name)
        assert c.units[i] == unit and c.std[i, 0] == pytest.approx(std, rel=1e-6)
    doubled = compare([small], sigma=2 * SIGMA)
    assert np.allclose(doubled.std, 2 * c.std, equal_nan=True)


def _fd(f, x, steps):
    cols = []
    for i, h in enumerate(steps):
        e = np.zeros_like(x)
        e[i] = h
        cols.append((f(x + e) - f(x - e)) / (2 * h))
    return np.stack(cols, axis=-1)


def test_tcp_std_matches_finite_differences(designs, model, task):
    """σ²(BᵀB)⁻¹ and J Σ Jᵀ rebuilt from finite differences of positions only."""
    small, _ = designs
    point = np.array([0.0, 0.05, 0.25])
    c = compare([small], sigma=SIGMA, task=task, task_point=point)
    params = model.nominal()
    free = np.flatnonzero([n in small.predicted_std for n in params.names])
    x0, steps = params.values, 1e-4 * params.scales[free]

    def full(x_free):
        x = x0.copy()
        x[free] = x_free
        return x

    b = _fd(lambda x: marker_positions(model, full(x), small.configurations).ravel(),
            x0[free], steps) / SIGMA
    cov = np.linalg.inv(b.T @ b)
    j = _fd(lambda x: evaluate(model.point_robot, task, full(x), point)[0][..., 0],
            x0[free], steps)
    tcp = np.sqrt(np.einsum("mip,pq,miq->m", j, cov, j)) * 1000.0
    assert np.allclose(c.task_std[:, 0], tcp, rtol=0.02)
    assert c.task_rms()[0] == pytest.approx(np.sqrt(np.mean(tcp ** 2)), rel=0.02)
    assert c.task_max()[0] == pytest.approx(tcp.max(), rel=0.02)


def test_identification_result_compares_with_its_design(designs, model):
    _, big = designs
    params = model.nominal()
    params = params.fixed([n for n in params.names if n not in big.predicted_std])
    meas = simulate(model, params.values, big.configurations, SIGMA, np.random.default_rng(1))
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        # every parameter the design predicts for (the selection would leave some of these
        # truly-nominal ones at nominal)
        result = identify(model, meas, params, settings=FitSettings(select="none", register=False))
    c = compare([big, result], ["design", "result"], sigma=SIGMA)
    assert c.kinds == ("design", "identification")
    ok = np.isfinite(c.std[:, 0])
    assert np.allclose(c.std[ok, 1], c.std[ok, 0], rtol=1e-2)
    own = compare([result])
    assert own.sigma_mm == (pytest.approx(SIGMA * 1000),)


def test_cli_writes_table_and_plot(designs, model, task, tmp_path, capsys):
    files = []
    for d, name in zip(designs, ["six", "twelve"]):
        d.to_json(tmp_path / f"{name}.json")
        files.append(str(tmp_path / f"{name}.json"))
    write_design(tmp_path / "task.csv", task, model.robot)
    table, png = tmp_path / "table.md", tmp_path / "bars.png"
    assert main(["compare", *files, "--task", str(tmp_path / "task.csv"), "--task-point",
                 "0,50,250", "--sigma", "0.02", "--out", str(table), "--plot", str(png)]) == 0
    text = table.read_text()
    assert "| parameter | unit | six | twelve |" in text and "| RMS (mm) |" in text
    assert png.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
    assert load_source(files[0]).model == MODEL
    capsys.readouterr()
    assert main(["compare", files[0], "--json"]) == 0
    assert '"doe_calib.comparison"' in capsys.readouterr().out


def test_not_a_design_is_refused(tmp_path):
    bad = tmp_path / "x.json"
    bad.write_text('{"format": "something"}')
    assert main(["compare", str(bad)]) == 2


def test_cli_writes_html_report(designs, model, task, tmp_path):
    files = []
    for d, name in zip(designs, ["six_poses", "twelve_poses"]):
        d.to_json(tmp_path / f"{name}.json")
        files.append(str(tmp_path / f"{name}.json"))
    write_design(tmp_path / "task.csv", task, model.robot)
    report = tmp_path / "compare.html"
    assert main(["compare", *files, "--task", str(tmp_path / "task.csv"), "--sigma", "0.02",
                 "--report", str(report)]) == 0
    text = report.read_text(encoding="utf-8")
    assert "six_poses" in text and "twelve_poses" in text
    assert text.count('src="data:image/png;base64,') == 2  # std bars and task accuracy bars
    assert "Predicted accuracy at the task poses" in text and "RMS" in text
    assert "http://" not in text and "https://" not in text  # self-contained
