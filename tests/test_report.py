"""HTML reports: structure, embedded figures, and rendering in headless Chromium."""
import base64
import io
import re
import shutil
import subprocess
import warnings
from html import escape

import numpy as np
import pytest
from matplotlib.image import imread

from doe_calib import build_model, examples, identify, simulate
from doe_calib.cli import main
from doe_calib.design import DesignConstraints, LineOfSight, LoadCase
from doe_calib.design.optimal import optimal_design
from doe_calib.model.loads import unloaded_and_loaded
from doe_calib.model.simulate import random_configurations, random_truth
from doe_calib.report import design_report, identification_report, write_report
from doe_calib.report.html import figure, table

IMG = re.compile(r'<img src="data:image/png;base64,([A-Za-z0-9+/=]+)" alt="([^"]*)"')
CHROMIUM = shutil.which("chromium")
TRACKER_MM = (2500.0, -800.0, 300.0)


def _images(html: str) -> list:
    """(alt text, RGB(A) array) of every embedded PNG."""
    return [(alt, imread(io.BytesIO(base64.b64decode(data)), format="png"))
            for data, alt in IMG.findall(html)]


@pytest.fixture(scope="module")
def identification(model6):
    rng = np.random.default_rng(3)
    q = random_configurations(model6.robot, 12, rng)
    cfg = unloaded_and_loaded(model6, model6.nominal().values, q, 250.0, (0.0, 0.1, 0.3))
    meas = simulate(model6, random_truth(model6, rng), cfg, 2e-5, rng)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        return identify(model6, meas), meas


@pytest.fixture(scope="module")
def identification_html(identification, model6, tmp_path_factory):
    result, meas = identification
    return identification_report(result, model6, meas,
                                 tmp_path_factory.mktemp("ident") / "identification.html")


@pytest.fixture(scope="module")
def design(robot6, tool6):
    model = build_model(robot6, tool6, "joint_offset")
    los = LineOfSight(tuple(v / 1000 for v in TRACKER_MM), np.radians(170.0),
                      ((0.0, 0.0, 1.0),) * tool6.n_markers)
    constraints = DesignConstraints(tuple(robot6.lower), tuple(robot6.upper),
                                    line_of_sight=los)
    return optimal_design(model, 6, [LoadCase(250.0, (0.0, 0.0, 0.2))], candidates=300,
                          constraints=constraints, refine=False, rng=np.random.default_rng(3))


@pytest.fixture(scope="module")
def design_html(design, tmp_path_factory):
    return design_report(design, tmp_path_factory.mktemp("design") / "design.html")


def test_identification_report_structure(identification, identification_html):
    result, _ = identification
    text = identification_html.read_text(encoding="utf-8")
    assert text.startswith("<!DOCTYPE html>") and "http" not in text  # self-contained
    images = _images(text)
    alts = [a for a, _ in images]
    for word in ("correlation", "joint positions, wrench", "per marker", "per pose"):
        assert sum(word in a for a in alts) == 1, word
    for alt, img in images:
        assert 150 <= img.shape[0] <= 3000 and 300 <= img.shape[1] <= 3000, alt
        assert img[..., :3].std() > 0.01, alt  # not blank
    for name in result.parameters.names:
        assert f'<td class="text">{name}</td>' in text
    # the fixed ones: one sentence, then every reason in a folded table
    n_fixed = int((~result.parameters.free).sum())
    assert f"{n_fixed} parameters fixed (" in text and "<details><summary>" in text
    folded = text.split("<details>", 1)[1].split("</details>", 1)[0]
    for reason in (r for r in result.parameters.fixed_reason if r):
        assert escape(reason) in folded
    assert "Levenberg" in text and "per coordinate" in text


def test_design_report_structure(design, design_html):
    text = design_html.read_text(encoding="utf-8")
    images = _images(text)
    alts = [a for a, _ in images]
    assert len(images) == 4
    for word in ("joint positions", "3-D view", "predicted standard deviation", "stick figure"):
        assert sum(word in a for a in alts) == 1, word
    for alt, img in images:
        assert 150 <= img.shape[0] <= 3000 and 300 <= img.shape[1] <= 3000, alt
        assert img[..., :3].std() > 0.01, alt
    for pose in design.poses():
        assert f'<td class="text">{pose["pose"]}</td>' in text
    for name in design.predicted_std:
        assert f'<td class="text">{name}</td>' in text
    assert "red: the tracker" in text and "line_of_sight / tracker" in text
    assert "certified bound" in text and "design_efficiency_at_least" in text
    assert "Robot in each pose" in text and 'alt="the robot as a stick figure' in text


def test_text_is_escaped_and_figures_embedded(tmp_path):
    png = b"\x89PNG fake"
    path = write_report(tmp_path / "r.html", "a <b> & c",
                        [("<script>", ["x < y", table(["n"], [["<i>"]]),
                                       figure(png, 'alt "q"', "cap <u>")])])
    text = path.read_text(encoding="utf-8")
    assert "<script>" not in text and "&lt;script&gt;" in text
    assert "<title>a &lt;b&gt; &amp; c</title>" in text and "x &lt; y" in text
    assert "&lt;i&gt;" in text and "cap &lt;u&gt;" in text and 'alt="alt &quot;q&quot;"' in text
    assert base64.b64encode(png).decode() in text


def test_design_command_writes_report(tmp_path, capsys):
    out, report = tmp_path / "design.json", tmp_path / "design.html"
    assert main(["design", "--robot", examples.ROBOT_URDF, "--tool", examples.TOOL_YAML,
                 "--model", "joint_offset", "--poses", "6", "--candidates", "200", "--no-refine",
                 "--seed", "3", "--out", str(out), "--report", str(report)]) == 0
    assert f"report: {report}" in capsys.readouterr().err
    assert len(_images(report.read_text(encoding="utf-8"))) == 4


def _render(html_path, tmp_path):
    """Screenshot (H, W, C) and dumped DOM of ``html_path`` in headless Chromium."""
    common = [CHROMIUM, "--headless", "--no-sandbox", "--disable-gpu", "--hide-scrollbars"]
    shot = tmp_path / "out.png"
    subprocess.run([*common, f"--screenshot={shot}", "--window-size=1200,3000",
                    html_path.as_uri()], check=True, capture_output=True, timeout=60)
    dom = subprocess.run([*common, "--virtual-time-budget=5000", "--dump-dom",
                          html_path.as_uri()], check=True, capture_output=True, timeout=60)
    return imread(shot), dom.stdout.decode("utf-8")


@pytest.fixture(scope="module")
def refine_html(robot6, tool6, tmp_path_factory):
    """A refine report (error falling, diagnosis sections) on data with a hidden cyclic error."""
    from doe_calib.diagnosis.refine import refine
    from doe_calib.report import refine_report

    rng = np.random.default_rng(3)
    true = build_model(robot6, tool6, "joint_offset+joint_compliance+cyclic(j3)")
    truth = random_truth(true, rng)
    cfg = unloaded_and_loaded(true, truth, random_configurations(robot6, 25, rng), 250,
                              (0, 0, 0.2))
    meas = simulate(true, truth, cfg, 3e-5, rng)
    out = refine(build_model(robot6, tool6, "joint_offset+joint_compliance"), meas)
    final = build_model(robot6, tool6, out.fit.model)
    return refine_report(out, final, meas, tmp_path_factory.mktemp("refine") / "refine.html")


@pytest.mark.skipif(CHROMIUM is None, reason="chromium is not installed")
@pytest.mark.parametrize("which", ["identification_html", "design_html", "refine_html"])
def test_report_renders_in_chromium(which, request, tmp_path):
    path = request.getfixturevalue(which)
    shot, dom = _render(path, tmp_path)
    assert shot.shape[0] >= 1000 and shot.shape[1] >= 1000
    assert shot[..., :3].std() > 0.02  # something is drawn, not a blank page
    n = len(IMG.findall(path.read_text(encoding="utf-8")))
    assert n >= 3 and len(re.findall(r'<img src="data:image/png;base64,', dom)) == n
    assert "<h1>" in dom and "</table>" in dom


def test_identify_command_writes_report(tmp_path, capsys):
    common = ["--robot", examples.ROBOT_URDF, "--tool", examples.TOOL_YAML,
              "--model", "joint_offset", "--sigma", "0.02"]
    data, report = tmp_path / "meas.csv", tmp_path / "identification.html"
    assert main(["simulate", *common, "--poses", "10", "--seed", "1", "--out", str(data)]) == 0
    assert main(["identify", *common, "--data", str(data), "--out", str(tmp_path / "r.json"),
                 "--report", str(report)]) == 0
    assert f"report: {report}" in capsys.readouterr().err
    assert len(_images(report.read_text(encoding="utf-8"))) == 4
