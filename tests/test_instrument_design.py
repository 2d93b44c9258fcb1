"""The design of plane touches and ballbar positions (issue #31, item 3): each plane or
pivot eliminated from the information of scalar readings, the exchange on it."""
import numpy as np
import pytest

from doe_calib.design.contacts import projected
from doe_calib.design.criteria import Criterion, log_det
from doe_calib.design.solvers.nuisance_exchange import nuisance_exchange, scalar_information


def _schur(rows, own, group):
    """M = A − C D⁻¹ Cᵀ of the information of (p, each group's 3 own parameters)."""
    k, f = rows.shape
    groups = int(group.max()) + 1
    jac = np.zeros((k, f + 3 * groups))
    jac[:, :f] = rows
    for i in range(k):
        jac[i, f + 3 * group[i]:f + 3 * group[i] + 3] = own[i]
    full = jac.T @ jac
    return full[:f, :f] - full[:f, f:] @ np.linalg.pinv(full[f:, f:]) @ full[f:, :f]


def test_scalar_information_is_the_schur_complement():
    rng = np.random.default_rng(4)
    rows, own, group = rng.normal(size=(20, 5)), rng.normal(size=(20, 3)), np.repeat([0, 1], 10)
    m = scalar_information(rows, own, group, np.arange(20))
    assert np.allclose(m, _schur(rows, own, group))
    # any fit on the own columns leaves more information: the relaxation's bound is one
    c = projected(rows[:, None], own, group, rng.uniform(size=20))[:, 0]
    assert np.linalg.eigvalsh(c.T @ c - m).min() > -1e-9
    assert np.allclose(scalar_information(rows, own, group, [0, 1, 2, 10, 11, 12]), 0)


def test_nuisance_exchange_swaps_on_the_exact_information():
    rng = np.random.default_rng(5)
    rows, own, group = rng.normal(size=(50, 4)), rng.normal(size=(50, 3)), rng.integers(0, 2, 50)
    crit = Criterion.from_name("D")
    start = np.flatnonzero(group == 0)[:5].tolist() + np.flatnonzero(group == 1)[:5].tolist()
    chosen, value, sweeps = nuisance_exchange(rows, own, group, start, crit)
    assert len(set(chosen.tolist())) == 10 and sweeps > 1
    assert value == pytest.approx(log_det(scalar_information(rows, own, group, chosen)))
    assert value > log_det(scalar_information(rows, own, group, start))
    for slot in range(10):  # no single swap does better
        for j in set(range(50)) - set(chosen.tolist()):
            other = chosen.copy()
            other[slot] = j
            assert log_det(scalar_information(rows, own, group, other)) <= value + 1e-9
