"""Compensation: joint values that make the identified robot reach a program's targets.

:mod:`.targets` reads the program, :mod:`.problem` builds the NLP once
(symbolic), :mod:`.solve` solves it row by row (numeric) and
:mod:`.result` holds what was found.
"""
from .problem import CompensationProblem, build_problem
from .result import CompensationResult, read_compensated_csv
from .solve import compensate, nominal_targets, tcp_point, tcp_std
from .targets import Targets, read_targets

__all__ = ["CompensationProblem", "CompensationResult", "Targets", "build_problem", "compensate",
           "nominal_targets", "read_compensated_csv", "read_targets", "tcp_point", "tcp_std"]
