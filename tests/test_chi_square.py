"""The χ² survival function and quantiles of ``estimation.chi_square`` equal SciPy's."""
import math

import numpy as np
import pytest
from fresh_interpreter import run_python
from scipy.special import chdtrc
from scipy.stats import chi2 as chi2_dist

from doe_calib.estimation.chi_square import chi2_quantile, chi2_survival

DOFS = [1, 2, 3, 5, 12, 29, 31, 100, 309, 1000, 12345, 99960, 300000]


@pytest.mark.parametrize("dof", DOFS)
def test_survival_is_scipy_chdtrc(dof):
    for ratio in (1e-3, 0.1, 0.5, 0.9, 0.99, 1.0, 1.01, 1.05, 1.2, 2.0, 5.0, 20.0):
        x = ratio * dof
        ref = float(chdtrc(dof, x))
        if ref > 1e-300:
            assert chi2_survival(x, dof) == pytest.approx(ref, rel=1e-12), (dof, ratio)


@pytest.mark.parametrize("dof", DOFS)
def test_quantile_is_scipy_ppf(dof):
    for prob in (1e-10, 1e-3, 0.025, 0.3, 0.5, 0.7, 0.975, 0.999, 1 - 1e-10):
        assert chi2_quantile(prob, dof) == pytest.approx(chi2_dist.ppf(prob, dof), rel=1e-12)


def test_far_tails_and_limits():
    # a 100 000-reading fit with σ̂/σ = 1.05: p ≈ 1e-230, still a number, as SciPy's
    dof = 300_000
    ref = float(chdtrc(dof, 1.05 ** 2 * dof))
    assert 0 < ref < 1e-200
    assert chi2_survival(1.05 ** 2 * dof, dof) == pytest.approx(ref, rel=1e-10)
    assert chi2_survival(0.0, 3) == 1.0 and chi2_survival(math.inf, 3) == 0.0
    assert chi2_survival(1e6, 3) == 0.0  # underflow, as SciPy
    q = chi2_quantile(0.975, 7)
    assert chi2_survival(q, 7) == pytest.approx(0.025, rel=1e-13)


def test_a_statistic_near_zero_on_many_dof():
    """A noise-free fit (χ² ≈ 1e-16 on hundreds of dof): p is 1, and its log factor finite."""
    for dof, x in ((682, 3.9e-16), (400, 1e-3), (2e5, 1.0)):
        assert chi2_survival(x, dof) == chdtrc(dof, x) == 1.0
    assert chi2_survival(50.0, 200) == pytest.approx(chdtrc(200, 50.0), rel=1e-9)


@pytest.mark.parametrize("bad", [(0.0, 3), (1.0, 3), (0.5, 0), (0.5, -2)])
def test_quantile_refuses_what_has_none(bad):
    with pytest.raises(ValueError):
        chi2_quantile(*bad)


def test_identify_loads_no_scipy(tmp_path):
    """The χ² figures of every fit no longer pull in scipy.special (0.15–0.2 s to import)."""
    code = ("import sys, numpy as np\n"
            "from doe_calib.estimation.fit_statistics import ratio_interval\n"
            "print(ratio_interval(350.0, 309))\n"
            "assert not any(m.startswith('scipy') for m in sys.modules), "
            "sorted(m for m in sys.modules if m.startswith('scipy'))[:5]\n")
    lo, hi = eval(run_python(code).strip().replace("(", "[").replace(")", "]"))
    assert lo < np.sqrt(350 / 309) < hi
