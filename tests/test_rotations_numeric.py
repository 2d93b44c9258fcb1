"""The NumPy rotation conversions and Kabsch registration against SciPy's ``Rotation``."""
import numpy as np
import pytest
from scipy.spatial.transform import Rotation

from doe_calib.estimation.registration import register
from doe_calib.model.rotations import matrix_to_rotation_vector, rotation_vector_to_matrix

RNG = np.random.default_rng(7)
# random turns, tiny ones (the series), and turns of π and near π about each axis
VECTORS = [*RNG.normal(size=(40, 3)), *(1e-5 * RNG.normal(size=(5, 3))), np.zeros(3),
           *(np.pi * np.eye(3)), *((np.pi - 1e-9) * np.eye(3)),
           np.pi * np.array([1.0, 1.0, 0.0]) / np.sqrt(2)]


@pytest.mark.parametrize("r", VECTORS)
def test_rotation_vector_to_matrix_is_scipys(r):
    assert np.allclose(rotation_vector_to_matrix(r), Rotation.from_rotvec(r).as_matrix(),
                       rtol=0, atol=1e-15)


@pytest.mark.parametrize("r", VECTORS)
def test_matrix_to_rotation_vector_is_scipys(r):
    m = Rotation.from_rotvec(r).as_matrix()
    ours, theirs = matrix_to_rotation_vector(m), Rotation.from_matrix(m).as_rotvec()
    # at exactly π, r and −r are the same turn
    same = np.allclose(ours, theirs, rtol=0, atol=1e-12) or (
        np.isclose(np.linalg.norm(theirs), np.pi) and np.allclose(ours, -theirs, atol=1e-12))
    assert same, (ours, theirs)


def test_stacked_rotation_vectors():
    r = RNG.normal(size=(4, 2, 3))
    assert np.allclose(rotation_vector_to_matrix(r),
                       Rotation.from_rotvec(r.reshape(-1, 3)).as_matrix().reshape(4, 2, 3, 3),
                       atol=1e-15)


def test_nearly_orthogonal_matrix_is_projected_as_scipy_does():
    m = Rotation.from_rotvec([0.3, -1.0, 2.0]).as_matrix() + 1e-7 * RNG.normal(size=(3, 3))
    assert np.allclose(matrix_to_rotation_vector(m), Rotation.from_matrix(m).as_rotvec(),
                       atol=1e-13)


def test_a_reflection_is_refused():
    with pytest.raises(ValueError, match="determinant"):
        matrix_to_rotation_vector(np.diag([1.0, 1.0, -1.0]))


@pytest.mark.parametrize("seed", range(5))
def test_register_is_scipys_kabsch(seed):
    rng = np.random.default_rng(seed)
    source = rng.normal(size=(6, 3))
    turn = Rotation.from_rotvec(rng.normal(size=3))
    target = turn.apply(source) + [0.5, -1.0, 2.0] + 1e-3 * rng.normal(size=(6, 3))
    w = rng.uniform(0.5, 2.0, size=6)
    r, t = register(source, target, w)
    cs, ct = np.average(source, axis=0, weights=w), np.average(target, axis=0, weights=w)
    expected = Rotation.align_vectors(target - ct, source - cs, weights=w)[0].as_matrix()
    assert np.allclose(r, expected, atol=1e-14)
    assert np.allclose(t, ct - expected @ cs, atol=1e-14)
    assert np.isclose(np.linalg.det(r), 1.0)


def test_register_of_a_mirrored_set_is_still_a_rotation():
    source = RNG.normal(size=(5, 3))
    r, _ = register(source, source * [1.0, 1.0, -1.0])
    expected = Rotation.align_vectors(source * [1.0, 1.0, -1.0] - (source * [1, 1, -1]).mean(0),
                                      source - source.mean(0))[0].as_matrix()
    assert np.isclose(np.linalg.det(r), 1.0)
    assert np.allclose(r, expected, atol=1e-12)
