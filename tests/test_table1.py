"""The Table I study: Monte Carlo against prediction, and the ordering of the two approaches."""
import json

import numpy as np

from studies import table1


def test_table1_small_run(tmp_path):
    reps = 150
    result = table1.run(tmp_path, repetitions=reps, spread_sets=3, seed=7, workers=2)
    # std of a std estimate from n draws is ~1/sqrt(2n) (5.8 % here): 25 % is > 4 of those
    for r in result["parameters"]:
        assert abs(r["std_pose"] / r["predicted_std_pose"] - 1) < 0.25, r
        assert abs(r["std_point"] / r["predicted_std_point"] - 1) < 0.25, r
        assert abs(r["bias_point"]) < 4.5 * r["predicted_std_point"] / np.sqrt(reps), r
    # Gauss–Markov: #2 is at least as precise for every parameter, every λ, every set
    for e in result["normalisation_sweep"]:
        assert all(v >= 1 - 1e-9 for v in e["improvement"].values()), e
    for s in result["spread"]:
        assert all(v >= 1 - 1e-9 for v in s["improvement"].values()), s
    saved = json.loads((tmp_path / "table1.json").read_text())
    assert {"parameters", "normalisation_sweep", "spread"} <= set(saved)
    assert {"name", "unit", "std_pose", "std_point", "predicted_std_pose",
            "predicted_std_point"} <= set(saved["parameters"][0])
    assert [p["name"] for p in saved["parameters"]] == list(table1.NAMES)
    assert (tmp_path / "table1.png").stat().st_size > 10_000
    assert "| dl1 (mm) |" in (tmp_path / "table1.md").read_text()
