"""The numeric settings of :func:`~doe_calib.diagnosis.diagnose` and
:func:`~doe_calib.diagnosis.refine.refine`, checked where they enter."""
from __future__ import annotations

from doe_calib.io.setting_ranges import at_least, fraction, positive, probability, whole


def check_settings(level, folds, min_gain, tolerance, practical_um, workers) -> None:
    """Refuse a setting out of its range, naming it (keyword names: ``level=5``).

    ``level`` is a probability in (0, 1); ``folds`` a whole number ≥ 2;
    ``min_gain`` a fraction in [0, 1); ``tolerance`` ≥ 0; ``practical_um`` > 0 µm;
    ``workers`` None or a whole number ≥ 1.

    Raises
    ------
    OptionError
        The first setting out of its range, with its value and the range allowed.
    """
    probability("level", level)
    whole("folds", folds, 2, "folds")
    fraction("min_gain", min_gain)
    at_least("tolerance", tolerance, 0.0)
    positive("practical_um", practical_um, "µm")
    if workers is not None:
        whole("workers", workers, 1, "thread")
