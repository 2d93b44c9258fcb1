"""A held-out reading without coordinates is compared to its socket's point, pivot or plane
as the kept readings place it."""
import numpy as np
import pytest

from doe_calib.diagnosis.held_out_contacts import (held_out_errors, held_out_rows, scored,
                                                   unscored_words)
from doe_calib.io.measurements import Configurations, Measurements


def _readings():
    """Five contacts (sockets A, A, A, B, B) and one tracker reading, σ 1, 1, 2, 1, 1, 1 mm."""
    q = np.zeros((6, 1))
    xyz = np.full((6, 3), np.nan)
    xyz[5] = [1.0, 2.0, 3.0]
    return Measurements(Configurations.from_arrays(q), np.arange(6), np.zeros(6, int), xyz,
                        np.array([1.0, 1.0, 2.0, 1.0, 1.0, 1.0]) * 1e-3, np.arange(2, 8),
                        socket=np.array([0, 0, 0, 1, 1, -1]), socket_names=("A", "B"))


def test_means_over_the_kept_contacts_weighted_by_sigma():
    m = _readings()
    v = np.arange(6.0)[:, None] * np.ones((1, 3))
    kept = np.array([False, True, True, True, False, True])
    e, can = held_out_errors(m, kept, v)
    # A: rows 1 (w 1) and 2 (w 1/4) → (1 + 2/4) / 1.25 = 1.2; B: row 3 alone
    assert np.allclose(e[:3, 0], 1.2 - v[:3, 0]) and np.allclose(e[3:5, 0], 3.0 - v[3:5, 0])
    assert can.all()
    d = held_out_rows(m, kept, v, v[:, :, None])  # the rows move as the errors do
    assert np.allclose(d[:5, 0, 0], -e[:5, 0]) and d[5, 0, 0] == 5.0


def test_a_socket_with_no_contact_kept_cannot_be_scored():
    m = _readings()
    kept = np.array([True, True, True, False, False, True])
    assert scored(m, kept).tolist() == [True, True, True, False, False, True]
    points = np.zeros((6, 3))
    e, can = held_out_errors(m, kept, points)
    assert np.all(e[3:5] == 0.0) and np.allclose(e[5], [1.0, 2.0, 3.0]) and not can[3]
    held = (~kept,)
    assert unscored_words(m, held) == ("; 2 contacts not scored (every other contact of their "
                                       "socket is in the same fold)")


def _touches_and_lengths():
    """Six touches of plane T (points near z = 0), five lengths and one seated contact of
    pivot P (about the origin, 0.3 m), and one tracker reading; σ 0.01 mm."""
    rng = np.random.default_rng(5)
    x = np.c_[rng.uniform(-0.2, 0.2, (6, 2)), rng.normal(scale=1e-5, size=6)]
    d = rng.normal(size=(5, 3))
    bar = 0.3 * d / np.linalg.norm(d, axis=1, keepdims=True)
    x = np.r_[x, bar, [[1e-5, 0.0, 0.0]], [[0.5, 0.5, 0.5]]]
    k = len(x)
    xyz = np.full((k, 3), np.nan)
    xyz[-1] = [0.5, 0.5, 0.5]
    plane = np.r_[np.zeros(6, int), -np.ones(7, int)]
    socket = np.r_[-np.ones(6, int), np.zeros(6, int), -1]
    distance = np.r_[np.full(6, np.nan), np.full(5, 0.3), np.nan, np.nan]
    m = Measurements(Configurations.from_arrays(np.zeros((k, 1))), np.arange(k),
                     np.zeros(k, int), xyz, np.full(k, 1e-5), np.arange(2, k + 2),
                     socket=socket, socket_names=("P",), plane=plane, plane_names=("T",),
                     distance=distance)
    return m, x


def test_held_out_rows_are_the_errors_derivative():
    """Points moving linearly with two parameters: the held-out touches' and lengths' errors,
    their plane and pivot placed by the kept readings, move by −D δ to first order."""
    m, x = _touches_and_lengths()
    b = np.random.default_rng(6).normal(scale=1e-3, size=(len(x), 3, 2))
    kept = np.ones(len(x), bool)
    kept[[0, 7]] = False
    d = held_out_rows(m, kept, x, b)
    h = 1e-4
    for p in range(2):
        step = np.zeros(2)
        step[p] = h
        up, down = (held_out_errors(m, kept, x + b @ (s * step))[0] for s in (1, -1))
        assert np.allclose((up - down) / (2 * h), -d[:, :, p], atol=1e-6)
    e, can = held_out_errors(m, kept, x)
    assert can.all()
    # a touch's and a length's error is one coordinate: along the normal, along the bar
    assert abs(e[0] @ [0, 0, 1]) == pytest.approx(np.linalg.norm(e[0]))
    assert abs(e[7] @ x[7]) == pytest.approx(np.linalg.norm(e[7]) * 0.3, rel=1e-3)


def test_a_plane_or_pivot_the_kept_readings_cannot_place_is_not_scored():
    m, _ = _touches_and_lengths()
    kept = np.ones(len(m), bool)
    kept[2:6] = False  # 2 touches kept of 6: the plane is not placed
    kept[11] = False  # 4 lengths, no seated contact: the pivot is placed
    assert scored(m, kept).tolist() == [False] * 6 + [True] * 7
    kept[6:8] = False  # 3 lengths
    assert scored(m, kept).tolist() == [False] * 12 + [True]
