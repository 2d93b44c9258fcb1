"""The Table II study: the paper's design as transcribed, and both designs against one bound."""
import json

import numpy as np

from studies.table2 import paper
from studies.table2.__main__ import main


def test_transcription_has_five_q2_angles_three_poses_each():
    q = paper.paper_design_deg()
    assert q.shape == (15, 6)
    values, counts = np.unique(q[:, 1], return_counts=True)
    assert sorted(values) == sorted(paper.Q2_GROUPS_DEG) and set(counts) == {3}
    assert np.all(np.abs(q[:, 4]) <= 125) and np.all(q[:, 2] <= 155)  # A5, A3 limits


def test_study_runs_and_no_design_beats_the_certified_bound(tmp_path):
    assert main(["--out", str(tmp_path), "--candidates", "1500"]) == 0

    r = json.loads((tmp_path / "table2.json").read_text())
    assert 0 < r["d_efficiency_paper_design"] <= 1 + 1e-9
    assert 0 < r["d_efficiency_optimised"] <= 1 + 1e-9
    assert r["d_efficiency_optimised"] > r["d_efficiency_paper_design"]
    names = [p["name"] for p in r["parameters"]]
    assert names == list(paper.TABLE_IV)
    for p in r["parameters"]:
        assert p["std_paper_design"] > 0 and p["std_optimised"] > 0
        assert p["unit"] == "µrad/(N·m)"
    assert "chi2_1" in (tmp_path / "table2.md").read_text()
    assert (tmp_path / "table2.png").stat().st_size > 10_000
