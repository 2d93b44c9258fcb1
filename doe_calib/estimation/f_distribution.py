"""The F distribution's survival function, without importing SciPy.

Every candidate effect of a diagnosis is tested by an F statistic
(:mod:`~doe_calib.diagnosis.effect_tests`). SciPy has its survival function
(``scipy.special.fdtrc``), but importing ``scipy.special`` costs 0.2–0.3 s, a
fifth of a whole ``diagnose``; here it is computed with ``math`` alone from the
regularized incomplete beta function

``P(F_{d1,d2} > f) = I_x(d2/2, d1/2)``,  ``x = d2 / (d2 + d1·f)``,

by its continued fraction (modified Lentz), on whichever of ``I_x(a, b)`` and
``1 − I_{1−x}(b, a)`` converges. The prefactor ``xᵃ (1 − x)ᵇ / (a B(a, b))`` is
formed in logarithms with Stirling's series for the large ``a`` of a large
campaign (d2 ≈ 3·10⁵), where ``lgamma(a + b) − lgamma(a)`` alone would lose ten
digits. Agreement with SciPy is checked to 1e-10 relative
(``tests/test_f_distribution.py``): 1e-12 and better away from ``x ≈ (a+1)/(a+b+2)``,
where the fraction switches branch and, for d2 ≈ 10⁵, keeps 11 digits.
"""
from __future__ import annotations

import math
import sys

from doe_calib.estimation.chi_square import stirling_error

_EPS = 1e-16
_TINY = 1e-300
_MAX_TERMS = 100_000


def _log_gamma_ratio(a: float, b: float) -> float:
    """log Γ(a + b) − log Γ(a), accurate for large ``a``."""
    if a < 15.0:
        return math.lgamma(a + b) - math.lgamma(a)
    # Stirling: log Γ(z) = (z − ½) log z − z + ½ log 2π + stirling_error(z)
    return ((a - 0.5) * math.log1p(b / a) + b * math.log(a + b) - b
            + stirling_error(a + b) - stirling_error(a))


def _log_prefactor(a: float, b: float, x: float, y: float) -> float:
    """log(xᵃ yᵇ / (a B(a, b))) with ``y = 1 − x`` given exactly by the caller."""
    if a >= b:
        log_beta = math.lgamma(b) - _log_gamma_ratio(a, b)
    else:
        log_beta = math.lgamma(a) - _log_gamma_ratio(b, a)
    log_x = math.log1p(-y) if x > 0.5 else math.log(x)  # x near 1: its digits are y's
    log_y = math.log1p(-x) if y > 0.5 else math.log(y)
    return a * log_x + b * log_y - log_beta - math.log(a)


def _fraction(a: float, b: float, x: float, y: float) -> float:
    """The continued fraction of I_x(a, b) (without its prefactor); x < (a+1)/(a+b+2).

    Its first denominator ``1 − (a+b)x/(a+1)`` nears 0 at that bound; it is formed
    from ``y = 1 − x`` as ``(1 − b + (a+b)y)/(a+1)`` when x is near 1, where ``1 − (a+b)x``
    would cancel ``log10(a)`` digits.
    """
    qab, qap, qam = a + b, a + 1.0, a - 1.0
    c = 1.0
    d = (1.0 - b + qab * y) / qap if x > 0.5 else 1.0 - qab * x / qap
    d = 1.0 / (_TINY if abs(d) < _TINY else d)
    h = d
    for m in range(1, _MAX_TERMS):
        m2 = 2 * m
        for an in (m * (b - m) * x / ((qam + m2) * (a + m2)),
                   -(a + m) * (qab + m) * x / ((a + m2) * (qap + m2))):
            d = 1.0 + an * d
            d = 1.0 / (_TINY if abs(d) < _TINY else d)
            c = 1.0 + an / c
            c = _TINY if abs(c) < _TINY else c
            delta = d * c
            h *= delta
        if abs(delta - 1.0) < _EPS:
            break
    return h


def _regularized_beta(a: float, b: float, x: float, y: float) -> float:
    """I_x(a, b) for 0 < x < 1, ``y = 1 − x``."""
    if x * (a + b + 2.0) < a + 1.0:
        return math.exp(_log_prefactor(a, b, x, y)) * _fraction(a, b, x, y)
    return 1.0 - math.exp(_log_prefactor(b, a, y, x)) * _fraction(b, a, y, x)


def f_survival(f: float, dfn: float, dfd: float) -> float:
    """P(F_{dfn, dfd} > f): the p-value of an F statistic (SciPy's ``fdtrc(dfn, dfd, f)``).

    Parameters
    ----------
    f : float
        The statistic (≥ 0; dimensionless).
    dfn, dfd : float
        Degrees of freedom of the numerator and the denominator (> 0).

    A p-value below the smallest normal double (2.2e-308) is 0, as SciPy's
    underflows there (its ``log`` is then −∞).
    """
    if dfn <= 0 or dfd <= 0:
        raise ValueError(f"F degrees of freedom must be positive, not ({dfn}, {dfd})")
    if f <= 0.0:
        return 1.0
    if math.isinf(f):
        return 0.0
    # x = dfd/(dfd + dfn f) and 1 − x = dfn f/(dfd + dfn f), each formed without cancellation
    total = dfd + dfn * f
    p = _regularized_beta(dfd / 2.0, dfn / 2.0, dfd / total, dfn * f / total)
    return p if p >= sys.float_info.min else 0.0  # underflow to 0 past the normal doubles
