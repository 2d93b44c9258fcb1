"""Numeric settings checked where they enter: a probability, a fraction, a count …

Each check returns the value (a float, or an int for :func:`whole`) or raises
:class:`~doe_calib.errors.OptionError` naming the setting, the value given and
the range allowed. A setting named like a command-line option (``"--level"``)
is said as the option and its text (``--level 5: …``); any other name as a
keyword argument (``level=5: …``). The command line's ``type=`` converters
(:mod:`doe_calib.cli.options`) and the settings objects share these checks, so
``doe-calib diagnose --level 5`` and ``DiagnosisSettings(level=5)`` refuse
the same value in the same words.

>>> probability("level", 0.01)
0.01
>>> whole("--folds", 5, 2)
5
"""
from __future__ import annotations

import math
import numbers

from doe_calib.errors import OptionError


def _said(name: str, value) -> str:
    if not name.startswith("-"):
        return f"{name}={value!r}"
    return f"{name} {value:g}" if isinstance(value, numbers.Real) else f"{name} {value}"


def _finite(name: str, value) -> float:
    if isinstance(value, bool) or not isinstance(value, numbers.Real):
        raise OptionError(f"{_said(name, value)}: must be a number")
    if not math.isfinite(value):
        raise OptionError(f"{_said(name, value)}: must be a finite number")
    return float(value)


def _unit(unit: str) -> str:
    return f" {unit}" if unit else ""


def positive(name: str, value, unit: str = "") -> float:
    """``value`` if it is a finite number > 0 (in ``unit``, said in the message)."""
    v = _finite(name, value)
    if not v > 0:
        raise OptionError(f"{_said(name, value)}: must be positive{_unit(unit)}")
    return v


def at_least(name: str, value, minimum: float, unit: str = "") -> float:
    """``value`` if it is a finite number ≥ ``minimum`` (e.g. a clearance of 0 mm or more)."""
    v = _finite(name, value)
    if not v >= minimum:
        raise OptionError(f"{_said(name, value)}: must be {minimum:g}{_unit(unit)} or more")
    return v


def probability(name: str, value) -> float:
    """``value`` if it is a probability strictly between 0 and 1 (a level, a power)."""
    v = _finite(name, value)
    if not 0.0 < v < 1.0:
        raise OptionError(f"{_said(name, value)}: must be a probability between 0 and 1, "
                          f"both excluded (e.g. 0.01)")
    return v


def fraction(name: str, value) -> float:
    """``value`` if it is a fraction from 0 (included) to 1 (excluded): a relative gain."""
    v = _finite(name, value)
    if not 0.0 <= v < 1.0:
        raise OptionError(f"{_said(name, value)}: must be a fraction from 0 to 1, 1 excluded "
                          f"(e.g. 0.02 for 2 %)")
    return v


def whole(name: str, value, minimum: int = 1, what: str = "") -> int:
    """``value`` if it is a whole number ≥ ``minimum`` (``what`` it counts, for the message)."""
    integral = isinstance(value, numbers.Integral) or (
        isinstance(value, numbers.Real) and math.isfinite(value) and float(value).is_integer())
    if isinstance(value, bool) or not integral:
        raise OptionError(f"{_said(name, value)}: must be a whole number")
    v = int(value)
    if v < minimum:
        raise OptionError(f"{_said(name, value)}: must be {minimum}{_unit(what)} or more")
    return v


def level_and_power(alpha, power, names=("alpha", "power")) -> tuple[float, float]:
    """``(alpha, power)`` if both are probabilities and the power is above the level:
    a test detects what it should with a probability above that of a false alarm.

    ``names``: how the two settings are named in the message.
    """
    alpha, power = probability(names[0], alpha), probability(names[1], power)
    if not alpha < power:
        raise OptionError(f"{_said(names[0], alpha)} and {_said(names[1], power)}: the power "
                          f"must be above the level (alpha < power)")
    return alpha, power
