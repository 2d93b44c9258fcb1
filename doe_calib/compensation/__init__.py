"""Compensation: joint values that make the identified robot reach a program's targets.

:mod:`.targets` reads the program, :mod:`.nlp` builds the NLP once
(symbolic), :mod:`.compensate` solves it row by row (numeric) and
:mod:`.result` holds what was found.
"""
from doe_calib.compensation.nlp import build_problem
from doe_calib.compensation.result import CompensationResult, read_compensated_csv
from doe_calib.compensation.compensate import compensate
from doe_calib.compensation.targets import Targets, read_targets

__all__ = ["CompensationResult", "Targets", "build_problem", "compensate", "read_compensated_csv",
           "read_targets"]
