"""A held-out contact is compared to its socket's point as the kept contacts place it."""
import numpy as np

from doe_calib.diagnosis.held_out_sockets import (held_out_errors, kept_socket_means, scored,
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
    means, can = kept_socket_means(m, kept, v)
    # A: rows 1 (w 1) and 2 (w 1/4) → (1 + 2/4) / 1.25 = 1.2; B: row 3 alone
    assert np.allclose(means[:3, 0], 1.2) and np.allclose(means[3:5, 0], 3.0)
    assert can.all() and means[5, 0] == 0.0


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
