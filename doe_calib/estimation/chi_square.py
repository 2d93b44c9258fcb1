"""The χ² distribution's survival function and quantiles, without importing SciPy.

Every identification reports the χ² p-value of its fit and the interval of
σ_true/σ (:mod:`~doe_calib.estimation.fit_statistics`). SciPy has both
(``scipy.special.chdtrc``, ``gammaincinv``), but importing ``scipy.special``
costs 0.15–0.2 s, more than a 60-pose fit itself: the command ``identify`` of
60 poses (``results/benchmarks.md`` (g)) takes 0.39 s CPU with this module and
0.58 s with ``scipy.special`` (1.08 s with ``scipy.stats``). Here they are
computed with ``math`` alone from the regularized incomplete gamma functions

``P(a, x) = γ(a, x)/Γ(a)``,  ``Q(a, x) = 1 − P(a, x)``,  χ²_ν sf(x) = Q(ν/2, x/2)

by the classic series (for ``x < a + 1``) and continued fraction (Lentz's
method, for ``x ≥ a + 1``). The common factor ``xᵃ e⁻ˣ / Γ(a)`` is formed for
large ``a`` as ``a·(log1p(u) − u) + ½ log(a/2π) − stirlerr(a)``, ``u = (x − a)/a``,
which avoids the cancellation of ``a log x − x − lgamma(a)`` (for a = 10⁵ that
cancellation alone would cost 10 digits). Agreement with SciPy is checked to
1e-12 relative over a ≈ 0.5 … 1.5·10⁵ and p down to 1e-300
(``tests/test_chi_square.py``). What only a diagnosis or a design asks (the
noncentral χ² of a test's power) is SciPy's.
"""
from __future__ import annotations

import math
from statistics import NormalDist

_EPS = 1e-16
_MAX_TERMS = 100_000


def stirling_error(a: float) -> float:
    """lgamma(a) − [(a − ½) log a − a + ½ log 2π], without the cancellation for large ``a``."""
    if a < 15.0:
        return math.lgamma(a) - ((a - 0.5) * math.log(a) - a + 0.5 * math.log(2 * math.pi))
    a2 = a * a
    return (1 / 12 - (1 / 360 - (1 / 1260 - (1 / 1680 - 1 / (1188 * a2)) / a2) / a2) / a2) / a


def log_factor(a: float, x: float) -> float:
    """log(xᵃ e⁻ˣ / Γ(a)), accurate also for large ``a`` with ``x`` near ``a``.

    Far below ``a`` (an exact fit's χ²) the plain form holds and the scaled one would
    take the log of 0.
    """
    if a < 15.0 or x < 1e-3 * a:
        return a * math.log(x) - x - math.lgamma(a)
    u = (x - a) / a
    return (a * (math.log1p(u) - u) + 0.5 * math.log(a / (2 * math.pi))
            - stirling_error(a))


def _lower_series(a: float, x: float) -> float:
    """P(a, x) by its series; for x < a + 1."""
    term = total = 1.0 / a
    n = a
    for _ in range(_MAX_TERMS):
        n += 1.0
        term *= x / n
        total += term
        if abs(term) < abs(total) * _EPS:
            break
    return total * math.exp(log_factor(a, x))


def _upper_fraction(a: float, x: float) -> float:
    """Q(a, x) by its continued fraction (modified Lentz); for x ≥ a + 1."""
    tiny = 1e-300
    b = x + 1.0 - a
    c = 1.0 / tiny
    d = 1.0 / b
    h = d
    for i in range(1, _MAX_TERMS):
        an = -i * (i - a)
        b += 2.0
        d = an * d + b
        d = tiny if abs(d) < tiny else d
        c = b + an / c
        c = tiny if abs(c) < tiny else c
        d = 1.0 / d
        delta = d * c
        h *= delta
        if abs(delta - 1.0) < _EPS:
            break
    return math.exp(log_factor(a, x)) * h


def regularized_gamma(a: float, x: float) -> tuple:
    """(P(a, x), Q(a, x)): the regularized lower and upper incomplete gamma functions."""
    if x <= 0.0:
        return 0.0, 1.0
    if math.isinf(x):
        return 1.0, 0.0
    if x < a + 1.0:
        p = _lower_series(a, x)
        return p, 1.0 - p
    q = _upper_fraction(a, x)
    return 1.0 - q, q


def chi2_survival(chi2: float, dof: float) -> float:
    """P(χ²_dof > chi2): the p-value of a χ² statistic (SciPy's ``chdtrc(dof, chi2)``).

    Parameters
    ----------
    chi2 : float
        The statistic (≥ 0; dimensionless).
    dof : float
        Degrees of freedom (> 0).
    """
    if dof <= 0:
        raise ValueError(f"χ² degrees of freedom must be positive, not {dof}")
    return regularized_gamma(dof / 2.0, chi2 / 2.0)[1]


def chi2_quantile(prob: float, dof: float) -> float:
    """The χ²_dof quantile: x with P(χ²_dof ≤ x) = ``prob`` (SciPy's ``chi2.ppf``).

    Parameters
    ----------
    prob : float
        Probability, 0 < prob < 1.
    dof : float
        Degrees of freedom (> 0).
    """
    if not 0.0 < prob < 1.0:
        raise ValueError(f"a χ² quantile needs 0 < prob < 1, not {prob}")
    return _quantile(1.0 - prob if prob > 0.5 else prob, prob > 0.5, prob, dof)


def chi2_upper_quantile(alpha: float, dof: float) -> float:
    """x with P(χ²_dof > x) = ``alpha``: a χ² test's critical value (SciPy's ``chdtri``).

    Parameters
    ----------
    alpha : float
        Upper-tail probability, 0 < alpha < 1.
    dof : float
        Degrees of freedom (> 0).
    """
    if not 0.0 < alpha < 1.0:
        raise ValueError(f"a χ² quantile needs 0 < alpha < 1, not {alpha}")
    return _quantile(alpha, True, 1.0 - alpha, dof)


def _quantile(target: float, upper: bool, prob: float, dof: float) -> float:
    """x with Q(x) = ``target`` (``upper``) or P(x) = ``target``; ``prob`` = P(x).

    Newton's method on whichever of P or Q is the smaller (so both tails keep
    their digits), started from the Wilson–Hilferty approximation.
    """
    if dof <= 0:
        raise ValueError(f"χ² degrees of freedom must be positive, not {dof}")
    a = dof / 2.0
    z = NormalDist().inv_cdf(prob)
    c = 1.0 / (9.0 * a)
    x = a * max(1.0 - c + z * math.sqrt(c), 0.1) ** 3  # Wilson–Hilferty, in x = χ²/2
    lo, hi = 0.0, math.inf
    for _ in range(200):
        p, q = regularized_gamma(a, x)
        f = (target - q) if upper else (p - target)  # increasing in x
        if f > 0:
            hi = x
        else:
            lo = x
        density = math.exp(log_factor(a, x)) / x
        step = f / density if density > 0 else math.inf
        new = x - step
        if not lo < new < hi:  # keep inside the bracket: bisect (geometric when unbounded)
            new = 0.5 * (lo + hi) if math.isfinite(hi) else 2.0 * x
            new = new if new > 0 else 0.5 * x
        if abs(new - x) <= 4 * _EPS * x:
            x = new
            break
        x = new
    return 2.0 * x


def noncentrality_for_power(dof: int, alpha: float, power: float) -> float:
    """λ at which the χ² test of ``dof`` degrees of freedom at level ``alpha`` has ``power``.

    The noncentrality of SciPy's noncentral χ² (``scipy.special.chndtrinc``) whose
    survival function at the test's critical value is ``power``.

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
    from scipy.special import chdtri, chndtrinc  # 0.15–0.2 s: a diagnosis or design only

    return float(chndtrinc(chdtri(dof, alpha), dof, 1.0 - power))
