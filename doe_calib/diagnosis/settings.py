"""The settings of :func:`~doe_calib.diagnosis.diagnose` and
:func:`~doe_calib.diagnosis.refine.refine`: frozen, each checked on construction."""
from __future__ import annotations

from dataclasses import dataclass

from doe_calib.diagnosis.cross_validation import GROUPINGS
from doe_calib.errors import OptionError
from doe_calib.io.setting_ranges import at_least, fraction, positive, probability, whole


@dataclass(frozen=True)
class DiagnosisSettings:
    """How :func:`~doe_calib.diagnosis.diagnose` tests a model and the effects it lacks.

    Attributes
    ----------
    level : float
        Significance level, a probability in (0, 1), Bonferroni-adjusted over every
        candidate and shape.
    folds : int
        Folds of the cross-validation (``pose`` and ``region`` groupings), ≥ 2.
    grouping : {"auto", "pose", "session", "region"}
        What a fold holds out (:mod:`~doe_calib.diagnosis.cross_validation`).
    cv_top : int
        Cross-validate every significant shape of this many (effect, joint) groups
        with the strongest evidence, ≥ 1.
    min_gain : float
        Material gain, a fraction in [0, 1): an effect is proposed only if it lowers
        the cross-validated RMS by at least this fraction.
    tolerance : float
        σ̂ within this fraction of σ (≥ 0), with no material candidate, is adequate
        even when the χ² test (too sharp at large N) rejects.
    practical_um : float
        Practical size, µm per coordinate (> 0): a misfit beyond the noise
        √(σ̂² − σ²) below it, with no material candidate, is adequate even when the
        χ² test and ``tolerance`` reject (the size is stated in the verdict).
    workers : int, optional
        Threads fitting the chosen candidates at once, ≥ 1 (default: the machine's
        cores, at most 4). The result does not depend on it
        (:mod:`~doe_calib.diagnosis.candidate_scoring`).

    Raises
    ------
    OptionError
        The first setting out of its range, with its value and the range allowed
        (``level=5: must be a probability …``).
    """

    level: float = 0.01
    folds: int = 5
    grouping: str = "auto"
    cv_top: int = 5
    min_gain: float = 0.02
    tolerance: float = 0.05
    practical_um: float = 2.0
    workers: int | None = None

    def __post_init__(self):
        if self.grouping not in GROUPINGS:
            raise OptionError(f"grouping={self.grouping!r}: choose one of "
                              f"{', '.join(GROUPINGS)}")
        checked = {"level": probability("level", self.level),
                   "folds": whole("folds", self.folds, 2, "folds"),
                   "cv_top": whole("cv_top", self.cv_top, 1),
                   "min_gain": fraction("min_gain", self.min_gain),
                   "tolerance": at_least("tolerance", self.tolerance, 0.0),
                   "practical_um": positive("practical_um", self.practical_um, "µm")}
        if self.workers is not None:
            checked["workers"] = whole("workers", self.workers, 1, "thread")
        for name, value in checked.items():
            object.__setattr__(self, name, value)


@dataclass(frozen=True)
class RefineSettings(DiagnosisSettings):
    """:class:`DiagnosisSettings` of each step of :func:`~doe_calib.diagnosis.refine.refine`,
    and ``max_steps``: the effects it adds at most, a whole number ≥ 0."""

    max_steps: int = 5

    def __post_init__(self):
        super().__post_init__()
        object.__setattr__(self, "max_steps", whole("max_steps", self.max_steps, 0, "effects"))
