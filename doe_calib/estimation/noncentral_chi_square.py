"""The noncentral χ² distribution: survival function and the noncentrality of a power.

A design's detectability (:mod:`~doe_calib.design.detectability`) asks for the
noncentrality λ at which a χ² test of ``dof`` degrees of freedom at level α
rejects with a given power. SciPy has the distribution (``scipy.special.chndtr``)
and a root finder, but importing ``scipy.special`` and ``scipy.optimize`` costs
0.4–0.5 s, a quarter of a whole ``diagnose``; here both are computed with
``math`` alone from the Poisson mixture

``P(χ²_{ν,λ} > x) = Σ_k Pois(k; λ/2) · Q(ν/2 + k, x/2)``,

whose terms are all positive (no cancellation). ``Q(a + k, y)`` follows from
``Q(a, y)`` by the upward recurrence ``Q(a + 1, y) = Q(a, y) + yᵃ e⁻ʸ / Γ(a + 1)``,
which adds positive terms only. Agreement with SciPy is checked to 1e-10
relative (``tests/test_noncentral_chi_square.py``).
"""
from __future__ import annotations

import functools
import math

from doe_calib.estimation.chi_square import chi2_upper_quantile, log_factor, regularized_gamma

_NEGLIGIBLE = 1e-18


def noncentral_chi2_survival(x: float, dof: float, nc: float) -> float:
    """P(χ²_{dof, nc} > x) (SciPy's ``1 − chndtr(x, dof, nc)``).

    Parameters
    ----------
    x : float
        The statistic (≥ 0; dimensionless).
    dof : float
        Degrees of freedom (> 0).
    nc : float
        Noncentrality λ (≥ 0).
    """
    if dof <= 0 or nc < 0:
        raise ValueError(f"noncentral χ² needs dof > 0 and λ ≥ 0, not ({dof}, {nc})")
    if x <= 0.0:
        return 1.0
    a, y, mu = dof / 2.0, x / 2.0, nc / 2.0
    q = regularized_gamma(a, y)[1]
    log_step = log_factor(a, y) - math.log(a)  # log of yᵃ e⁻ʸ / Γ(a + 1)
    total = 0.0
    k = 0
    while True:
        log_weight = -mu + (k * math.log(mu) if mu > 0 else 0.0) - math.lgamma(k + 1.0)
        weight = math.exp(log_weight)
        total += weight * q
        if k >= mu and (weight < _NEGLIGIBLE * max(total, _NEGLIGIBLE) or mu == 0):
            return min(total, 1.0)
        q = min(q + math.exp(log_step), 1.0)
        log_step += math.log(y) - math.log(a + k + 1.0)
        k += 1


@functools.lru_cache(maxsize=256)  # a pure function of three numbers, asked per candidate
def noncentrality_for_power(dof: int, alpha: float, power: float) -> float:
    """λ at which the χ² test of ``dof`` degrees of freedom at level ``alpha`` has ``power``.

    Bisection on λ (the power increases with λ) to 1e-13 relative.

    Parameters
    ----------
    dof : int
        Degrees of freedom of the test (≥ 1).
    alpha : float
        The test's level, 0 < alpha < 1.
    power : float
        The probability of rejecting, 0 < power < 1; 0 when ``power ≤ alpha``.

    >>> round(noncentrality_for_power(1, 0.05, 0.8), 3)   # (1.96 + 0.8416)²
    7.849
    """
    if power <= alpha:
        return 0.0
    critical = chi2_upper_quantile(alpha, dof)
    lo, hi = 0.0, 1.0
    while noncentral_chi2_survival(critical, dof, hi) < power:
        lo, hi = hi, 2.0 * hi
    while hi - lo > 1e-13 * hi:
        mid = 0.5 * (lo + hi)
        if noncentral_chi2_survival(critical, dof, mid) < power:
            lo = mid
        else:
            hi = mid
    return 0.5 * (lo + hi)
