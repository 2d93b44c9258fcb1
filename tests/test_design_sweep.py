"""The design sweep: same numbers on local processes and on a local Dask cluster; sane figures."""
import json

import numpy as np
import pytest

from studies.design_sweep import report, sweep


def _numbers(points):
    """Everything a design point returns except its running time."""
    return [{k: v for k, v in p.items() if k != "seconds"} for p in points]


@pytest.fixture(scope="module")
def local():
    return sweep.run(quick=True, workers=2)


def test_quick_grid_is_small_and_seeded_per_robot():
    tasks = sweep.grid(quick=True)
    assert 2 <= len(tasks) <= 3
    assert all(t.candidates == sweep.QUICK_CANDIDATES and not t.refine for t in tasks)
    seeds = {t.robot: t.seed for t in tasks}
    assert all(t.seed == seeds[t.robot] for t in tasks) and len(set(seeds.values())) == 2
    assert sweep.grid(quick=True) == tasks


def test_local_dask_cluster_gives_the_same_numbers(local):
    distributed = pytest.importorskip("distributed")
    seen = []
    with distributed.LocalCluster(n_workers=2, threads_per_worker=1, processes=True,
                                  dashboard_address=None) as cluster:
        on_dask = sweep.run(quick=True, scheduler=cluster.scheduler_address,
                            progress=lambda done, total, note: seen.append((done, total)))
    assert _numbers(on_dask["points"]) == _numbers(local["points"])
    assert seen[-1] == (3, 3)


def test_efficiencies_and_std_against_n(local):
    points = local["points"]
    for p in points:
        assert 0.0 < p["d_efficiency"] <= 1.0 and 0.0 < p["efficiency"] <= 1.0
        assert p["random_equivalent"] >= p["n_poses"]
        assert all(np.isfinite(v) and v > 0 for v in p["median_std"].values())
    small, large = sorted((p for p in points if p["robot"] == "three_dof"),
                          key=lambda p: p["n_poses"])
    assert small["n_poses"] < large["n_poses"] and small["criterion"] == large["criterion"]
    for block, std in large["median_std"].items():
        assert std <= small["median_std"][block] * (1 + 1e-9), block
    assert all(s < 0 for s in local["findings"]["slopes"]["three_dof/r100/D"].values())


def test_report_writes_table_and_figure(local, tmp_path):
    text = report.markdown(json.loads(json.dumps(local)))
    assert "| tool | criterion | N |" in text and "## Conclusions" in text
    report.plot(local, tmp_path / "sweep.png")
    assert (tmp_path / "sweep.png").read_bytes()[:4] == b"\x89PNG"
