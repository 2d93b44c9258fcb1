"""Parallel engines give the same numbers: serial, local processes, and a local Dask cluster."""
import numpy as np
import pytest

from doe_calib.errors import DoeCalibError
from doe_calib.runtime.parallel import run_tasks, task_seeds
from studies import table1


def _draw(seed):
    return np.random.default_rng(seed).normal(size=3)


def test_results_follow_the_tasks_not_the_engine():
    seeds = task_seeds(5, 6)
    assert len(set(seeds)) == 6
    serial = run_tasks(_draw, seeds, workers=1)
    local = run_tasks(_draw, seeds, workers=2)
    assert np.array_equal(np.array(serial), np.array(local))
    assert np.array_equal(serial[3], _draw(seeds[3]))


def test_monte_carlo_on_a_local_dask_cluster_matches_local_processes():
    distributed = pytest.importorskip("distributed")
    model, truth = table1.setup()
    cfg = table1.random_configurations(np.random.default_rng(1))
    local = table1.monte_carlo(cfg, 60, 11, 0.1, workers=2)
    seen = []
    with distributed.LocalCluster(n_workers=2, threads_per_worker=1, processes=True,
                                  dashboard_address=None) as cluster:
        on_dask = table1.monte_carlo(cfg, 60, 11, 0.1, scheduler=cluster.scheduler_address,
                                     progress=lambda done, total, note: seen.append(done))
    for a in ("pose", "point"):
        assert on_dask[a].shape == (60, 6)
        assert np.array_equal(on_dask[a], local[a])
    assert seen[-1] == 60
    # and the estimates are estimates: spread of the order of the predicted std
    pred = np.sqrt(np.diag(table1.predict_covariance(model, truth, cfg, table1.SIGMA).covariance))
    ratio = on_dask["point"].std(axis=0, ddof=1) / (pred * table1.TO_UNIT)
    assert np.all((ratio > 0.6) & (ratio < 1.5)), ratio


def test_a_dask_worker_with_four_threads_matches_the_serial_run(monkeypatch):
    """Several identifications at once in one worker process (one model, built once, shared
    by its threads): the numbers of a serial run."""
    distributed = pytest.importorskip("distributed")
    monkeypatch.setattr(table1, "_CHUNK", 5)  # 8 tasks for the 4 threads
    cfg = table1.random_configurations(np.random.default_rng(2))
    serial = table1.monte_carlo(cfg, 40, 13, 0.1, workers=1)
    with distributed.LocalCluster(n_workers=1, threads_per_worker=4, processes=True,
                                  dashboard_address=None) as cluster:
        on_dask = table1.monte_carlo(cfg, 40, 13, 0.1, scheduler=cluster.scheduler_address)
    for a in ("pose", "point"):
        assert np.array_equal(on_dask[a], serial[a])


def test_unreachable_scheduler_is_reported_in_words():
    pytest.importorskip("distributed")
    with pytest.raises(DoeCalibError, match="cannot reach the Dask scheduler"):
        run_tasks(_draw, [1, 2], scheduler="tcp://127.0.0.1:9", connect_timeout=1)



def test_threads_evaluating_one_model_at_once_get_their_own_numbers(robot6, tool6):
    """What a Dask worker with several threads does: evaluation buffers are per thread."""
    from concurrent.futures import ThreadPoolExecutor

    from doe_calib import Configurations, build_model
    from doe_calib.model.evaluation import marker_positions
    from doe_calib.model.simulate import random_configurations

    rng = np.random.default_rng(6)
    model = build_model(robot6, tool6, "joint_offset")
    cfg = Configurations.from_arrays(random_configurations(robot6, 400, rng))
    values = [model.nominal().values + rng.normal(0, 1e-2, model.n_parameters)
              for _ in range(8)]
    expected = [marker_positions(model, v, cfg) for v in values]

    def check(i):
        return all(np.array_equal(marker_positions(model, values[i % 8], cfg), expected[i % 8])
                   for _ in range(30))

    with ThreadPoolExecutor(4) as pool:
        assert all(pool.map(check, range(16)))
