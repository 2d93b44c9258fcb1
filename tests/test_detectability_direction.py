"""The invisible direction an effect reports is the same whichever basis of its null space
the SVD returns (a null space of two or more dimensions has no preferred basis)."""
import numpy as np

from doe_calib.design.detectability import null_direction


def _rotated_svd(a, rng):
    """An SVD of ``a`` whose null-space rows are rotated at random (still an SVD)."""
    _, s, vt = np.linalg.svd(a, full_matrices=False)
    null = s < 1e-9
    q, _ = np.linalg.qr(rng.standard_normal((null.sum(), null.sum())))
    vt = vt.copy()
    vt[null] = q @ vt[null]
    return np.where(null, 0.0, s), vt


def test_null_direction_does_not_depend_on_the_basis():
    rng = np.random.default_rng(3)
    a = rng.standard_normal((40, 6)) @ np.diag([1, 1, 1, 1, 0, 0]) @ np.linalg.qr(
        rng.standard_normal((6, 6)))[0]
    # independent truth: the projector onto the null space, and the unit vector it keeps most
    projector = np.eye(6) - np.linalg.pinv(a) @ a
    k = int(np.argmax(np.diag(projector)))
    truth = projector[:, k] / np.linalg.norm(projector[:, k])
    for _ in range(5):
        d = null_direction(*_rotated_svd(a, rng))
        np.testing.assert_allclose(d, truth, atol=1e-9)
        assert d[k] > 0


def test_one_dimensional_null_space_keeps_the_svd_vector():
    rng = np.random.default_rng(4)
    a = rng.standard_normal((30, 4))
    a[:, 3] = a[:, :3] @ np.array([0.5, -1.0, 2.0])
    _, s, vt = np.linalg.svd(a, full_matrices=False)
    np.testing.assert_array_equal(null_direction(s, vt), vt[-1])
    np.testing.assert_allclose(a @ null_direction(s, vt), 0.0, atol=1e-9)


def test_null_direction_shows_no_rounding_noise():
    # null space span(e0 + e1, e2): the direction is e2, exactly, whatever the basis
    rng = np.random.default_rng(5)
    a = rng.standard_normal((20, 5))
    a[:, 1] = -a[:, 0]
    a[:, 2] = 0.0
    for _ in range(5):
        np.testing.assert_array_equal(null_direction(*_rotated_svd(a, rng)), [0, 0, 1, 0, 0])
