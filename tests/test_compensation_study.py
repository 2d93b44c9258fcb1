"""The compensation study writes its table, figures and JSON, with the figures the README quotes."""
import json

from doe_calib.cli import main


def test_study_through_the_cli(tmp_path):
    assert main(["study", "compensation", "--out", str(tmp_path)]) == 0
    s = json.loads((tmp_path / "compensation.json").read_text())
    assert s["rms_mm"]["nominal"] > 1.0 and s["rms_reached_mm"] <= 0.03
    assert s["largest_ratio_reached"] <= 2.0 and s["converged"] >= s["targets"] - 1
    assert "not reached" in (tmp_path / "compensation.md").read_text() or not s["not_reached"]
    assert (tmp_path / "compensation.png").stat().st_size > 10_000
