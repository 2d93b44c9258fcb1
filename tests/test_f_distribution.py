"""The F survival function of ``estimation.f_distribution`` equals SciPy's ``fdtrc``."""
import math

import numpy as np
import pytest
from scipy.special import fdtrc

from doe_calib.estimation.f_distribution import f_survival

DFN = [1, 2, 3, 5, 7, 12, 30, 69]
DFD = [1, 2, 5, 10, 31, 100, 309, 1000, 12345, 99960, 300000]


@pytest.mark.parametrize("dfn", DFN)
def test_survival_is_scipy_fdtrc_on_a_grid(dfn):
    for dfd in DFD:
        for f in (1e-3, 0.1, 0.5, 0.9, 1.0, 1.1, 2.0, 5.0, 20.0, 100.0, 1e3, 1e4):
            ref = float(fdtrc(dfn, dfd, f))
            if ref > 1e-300:
                assert f_survival(f, dfn, dfd) == pytest.approx(ref, rel=1e-10), (dfn, dfd, f)


def test_survival_is_scipy_fdtrc_at_random_points():
    rng = np.random.default_rng(7)
    worst = 0.0
    for _ in range(2000):
        dfn, dfd = int(rng.integers(1, 15)), int(10 ** rng.uniform(0, 5.5))
        f = 10 ** rng.uniform(-2, 2)
        ref = float(fdtrc(dfn, dfd, f))
        if ref > 1e-300:
            worst = max(worst, abs(f_survival(f, dfn, dfd) - ref) / ref)
    assert worst < 1e-10


def test_far_tail_limits_and_errors():
    # a candidate that explains the residual: p ≈ 1e-200, still a number, as SciPy's
    ref = float(fdtrc(3, 300, 600.0))
    assert 0 < ref < 1e-100
    assert f_survival(600.0, 3, 300) == pytest.approx(ref, rel=1e-11)
    assert f_survival(0.0, 3, 30) == 1.0 and f_survival(math.inf, 3, 30) == 0.0
    assert f_survival(1e200, 3, 300) == 0.0  # underflow, as SciPy
    assert f_survival(12572.6, 3, 300) == 0.0 == fdtrc(3, 300, 12572.6)  # p ≈ 5e-315
    # F(1, d) = t² with d dof: P(F > t²) = 2 P(T > t); for d = 1 the t is Cauchy
    assert f_survival(1.0, 1, 1) == pytest.approx(0.5, rel=1e-14)
    assert f_survival(3.0, 1, 1) == pytest.approx(1.0 - 2.0 / math.pi * math.atan(3 ** 0.5),
                                                  rel=1e-13)
    with pytest.raises(ValueError):
        f_survival(1.0, 0, 5)
