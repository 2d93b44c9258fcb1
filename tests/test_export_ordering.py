"""Pose ordering: the nearest-neighbour + 2-opt + or-opt path against exhaustive search."""
import itertools
from dataclasses import replace

import numpy as np
import pytest

from doe_calib.export.ordering import DEFAULT_SPEED, axis_speeds, move_times, path_time, short_path


def _brute_force(times, start):
    return min(path_time(times, p, start) for p in itertools.permutations(range(len(times))))


@pytest.mark.parametrize("with_start", [False, True])
def test_within_a_few_percent_of_brute_force(with_start):
    rng = np.random.default_rng(11)
    ratios = []
    for _ in range(40):
        m = int(rng.integers(3, 9))
        q, speed = rng.uniform(-3, 3, (m, 6)), rng.uniform(1, 3, 6)
        times = move_times(q, q, speed)
        start = move_times(rng.uniform(-3, 3, (1, 6)), q, speed)[0] if with_start else None
        order = short_path(times, start)
        assert sorted(order.tolist()) == list(range(m))
        ratios.append(path_time(times, order, start) / _brute_force(times, start))
    assert min(ratios) >= 1 - 1e-12
    assert max(ratios) <= 1.05 and np.mean(ratios) <= 1.01


def test_never_longer_than_the_given_order():
    rng = np.random.default_rng(2)
    for m in (2, 10, 40):
        q = rng.uniform(-3, 3, (m, 6))
        times = move_times(q, q, np.ones(6))
        assert path_time(times, short_path(times)) <= path_time(times, range(m)) + 1e-12


def test_weighted_by_the_slowest_axis():
    q = np.array([[0.0, 0.0], [1.0, 0.0], [0.0, 1.0]])
    assert move_times(q[1:2], q[2:], [1.0, 0.25]).item() == pytest.approx(4.0)
    # moving axis 2 is 4× slower: from pose 0, visit pose 1 (axis 1) before 2
    assert short_path(move_times(q, q, [1.0, 0.25]),
                      move_times(q[:1], q, [1.0, 0.25])[0]).tolist() == [0, 1, 2]


def test_speeds_from_the_urdf_or_the_default(robot6):
    assert axis_speeds(robot6).tolist() == [1.8, 1.8, 1.8, 2.2, 2.2, 3.2]
    slow = replace(robot6, joints=tuple(replace(j, velocity=0.0) for j in robot6.joints))
    assert axis_speeds(slow).tolist() == [DEFAULT_SPEED["revolute"]] * 6
