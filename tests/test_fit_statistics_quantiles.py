"""The χ² p-value and σ̂/σ interval of ``fit_statistics`` equal scipy.stats' (which they no
longer import: scipy.special gives the same functions)."""
from types import SimpleNamespace

import numpy as np
import pytest
from scipy.stats import chi2 as chi2_dist

from doe_calib.estimation.fit_statistics import fit_statistics, ratio_interval


@pytest.mark.parametrize("chi2, dof", [(5.0, 3), (350.0, 309), (1.2e5, 1.0e5 - 40), (0.5, 1)])
def test_ratio_interval_is_scipy_stats(chi2, dof):
    lo, hi = ratio_interval(chi2, dof, 0.95)
    assert lo == pytest.approx(np.sqrt(chi2 / chi2_dist.ppf(0.975, dof)), rel=1e-13)
    assert hi == pytest.approx(np.sqrt(chi2 / chi2_dist.ppf(0.025, dof)), rel=1e-13)
    assert lo < np.sqrt(chi2 / dof) < hi


class _Free(list):
    @property
    def free(self):
        return np.array(self)


@pytest.mark.parametrize("ratio, n_obs", [(1.1, 360), (1.02, 300006), (0.9, 12)])
def test_fit_statistics_p_value_is_scipy_stats(ratio, n_obs):
    result = SimpleNamespace(parameters=_Free([True] * 8 + [False] * 3), convergence={},
                             n_observations=n_obs, sigma_ratio=ratio, sigma_source="given")
    stats = fit_statistics(result)
    dof = n_obs - 8
    assert stats.dof == dof and stats.chi2 == pytest.approx(ratio ** 2 * dof, rel=1e-15)
    assert stats.p_value == pytest.approx(chi2_dist.sf(ratio ** 2 * dof, dof), rel=1e-12)
    assert stats.sigma_ratio_interval == pytest.approx(ratio_interval(stats.chi2, dof))
