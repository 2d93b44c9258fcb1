"""What a new user hit on the way (issue #30, item 8), each mended."""
import tomllib
from pathlib import Path

import pytest

from doe_calib.cli import main

ROOT = Path(__file__).resolve().parent.parent


def test_version_is_the_package_version(capsys):
    with pytest.raises(SystemExit) as stop:
        main(["--version"])
    assert stop.value.code == 0
    version = tomllib.loads((ROOT / "pyproject.toml").read_text())["project"]["version"]
    assert capsys.readouterr().out.strip() == f"doe-calib {version}"


def test_fit_statistics_show_as_their_summary_in_a_notebook():
    """IPython's plain-text view (``_repr_pretty_``) is the statistics' lines, not the
    dataclass's one-line repr."""
    from doe_calib.estimation.fit_statistics import FitStatistics

    stats = FitStatistics(readings=10, observations=30, free=6, fixed=0, chi2=25.0, dof=24,
                          p_value=0.4, sigma_ratio=1.02, sigma_ratio_interval=(0.8, 1.4),
                          sigma_source="given", jacobian_evaluations=4,
                          residual_evaluations=5, iterations=4, converged=True, message="ok")
    shown = []

    class Printer:
        text = shown.append

    stats._repr_pretty_(Printer(), False)
    assert shown == [stats.summary()]
    assert "degrees of freedom     = 24" in shown[0] and "FitStatistics(" not in shown[0]


def test_readme_states_the_demo_figures_it_prints(tmp_path):
    """The README's first paragraph gives the held-out error before and after refine as the
    demo (its default settings) prints them."""
    import re

    from doe_calib.examples.demo import run_demo

    text = " ".join((ROOT / "README.md").read_text().split())
    before, after = re.search(r"held-out error fall from ([\d.]+) mm to ([\d.]+) mm",
                              text).groups()
    out = run_demo(tmp_path / "demo", say=lambda s: None)
    rms = list(out["held_out_rms_mm"].values())
    assert (f"{rms[0]:.{len(before) - 2}f}", f"{rms[-1]:.{len(after) - 2}f}") == (before, after)
    page = Path(out["report"]).read_text(encoding="utf-8")
    # the final model is adequate: its report does not send the user after a trend of noise
    final = page.split("Final model: ")[1]
    assert "The model is adequate: its residual is at the noise level" in final
    assert "The residual size follows" not in final
    # the compensated program's table is preformatted text, not a run-on paragraph
    assert re.search(r"The compensated program</h2>\s*<pre>", page)


@pytest.mark.skipif(__import__("shutil").which("chromium") is None,
                    reason="chromium is not installed")
def test_a_wide_table_stays_inside_the_page(tmp_path):
    """A candidate table with long effect strings wraps inside the page (1100 px wide, centred
    in a 1400 px window) instead of running past it and clipping its last column."""
    import subprocess

    from matplotlib.pyplot import imread

    from doe_calib.report.html import section, table, write_report

    effect = "compliance_by_angle(j2,nodes_deg=-138.002;-50.9495;-7.0019;12.5;40.25)"
    header = ["#", "effect", "in words", "F", "dof", "p", "explains (%)", "CV RMS",
              "fitted size ± std", "decision"]
    rows = [[i, effect, "a compliance of joint 2 that changes with its angle", 4928.1, "2, 231",
             1.27e-304, 99.77, "0.7499 → 0.03645 mm (−95.1 %)",
             "chi_a2_1 = 0.4503 ± 0.0015 µrad/(N·m); chi_a2_2 = 0.3367 ± 0.0034 µrad/(N·m)",
             f"{effect} predicts better"] for i in range(4)]
    page = write_report(tmp_path / "t.html", "wide", [section("Candidates", table(header, rows))])
    shot = tmp_path / "t.png"
    subprocess.run(["chromium", "--headless", "--no-sandbox", "--disable-gpu",
                    "--hide-scrollbars", f"--screenshot={shot}", "--window-size=1400,1500",
                    page.as_uri()], check=True, capture_output=True, timeout=60)
    image = imread(shot)[..., :3]
    drawn = (image < 0.8).any(axis=(0, 2))
    assert drawn[:700].any()  # the table is drawn
    assert not drawn[1265:].any()  # nothing right of the page's 1100 px (150 … 1250)


def test_a_payload_without_a_size_is_said_to_be_drawn_as_a_steel_sphere():
    from doe_calib.design.notes import collision_words
    from doe_calib.design.result import CandidateCount

    collision = {"clearance_mm": 20, "self_clearance_mm": 5, "pairs_checked": 87,
                 "pairs_not_checked": []}
    count = CandidateCount(drawn=100, kept=90, removed={})
    said = collision_words(collision, count, (), ["250@0,0,200", "0@0,0,0", "40@0,0,100:150"])
    radius_mm = 1000 * (3 * 250 / (4 * 3.141592653589793 * 7850)) ** (1 / 3)  # steel, 7850 kg/m³
    assert f"the 250 kg payload is drawn as a steel sphere of radius {radius_mm:.0f} mm" in said
    assert "--load 250@0,0,200:R_MM" in said
    assert said.count("steel sphere") == 1  # not the massless load, not the one with a size


def test_export_writes_its_file_again_and_never_over_its_input(tmp_path, capsys):
    from doe_calib import examples

    design = tmp_path / "d.json"
    assert main(["design", "--robot", examples.THREE_DOF_URDF, "--tool",
                 examples.THREE_DOF_TOOL_YAML, "--model", "joint_offset", "--poses", "4",
                 "--candidates", "200", "--seed", "1", "--no-collision", "--out",
                 str(design)]) == 0
    out = tmp_path / "program.csv"
    for _ in range(2):  # the second run replaced the file; it said "is a file, not a folder"
        assert main(["export", str(design), "--format", "poses", "--out", str(out)]) == 0
    assert out.is_file()
    capsys.readouterr()
    assert main(["export", str(design), "--format", "poses", "--out", str(design)]) == 2
    assert "is the input" in capsys.readouterr().err
