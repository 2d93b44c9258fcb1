"""The toolkit's exceptions and warnings: one base class, a few named kinds.

Errors are raised where bad input enters (with file, line and column when it
comes from a file); warnings report numerical trouble in words a user can act
on.
"""
from __future__ import annotations


class DoeCalibError(Exception):
    """Base class of every error raised by doe_calib."""


class DataError(DoeCalibError):
    """Bad input data: a measurement, tool, design or result file.

    Parameters
    ----------
    message : str
        What is wrong and, where it helps, how to fix it.
    path, line, column : optional
        Where the problem is (1-based line; column name or 1-based number).
    """

    def __init__(self, message: str, path=None, line=None, column=None):
        self.path, self.line, self.column = path, line, column
        where = ""
        if path is not None:
            where = str(path)
            if line is not None:
                where += f", line {line}"
            if column is not None:
                where += f", column {column}"
            where += ": "
        super().__init__(where + message)


class ModelError(DoeCalibError):
    """A robot, tool or effect description that cannot make a model."""


class OptionError(DoeCalibError):
    """A setting that cannot be used: a command-line option or a keyword argument
    out of its range, an unknown parameter name, an output file that cannot be written."""


class SolverError(DoeCalibError):
    """An estimation or design problem that could not be solved."""


class CollisionError(DoeCalibError):
    """A robot program whose moves would collide (naming the move and the pair)."""


class DoeCalibWarning(UserWarning):
    """Base class of every warning issued by doe_calib.

    ``warnings.simplefilter("ignore", DoeCalibWarning)`` silences the toolkit's
    warnings and leaves numpy's, scipy's and CasADi's alone; ``"error"`` turns
    them into exceptions.
    """


class IdentifiabilityWarning(DoeCalibWarning):
    """Some parameters cannot be separated by the data and were fixed."""


class ConditioningWarning(DoeCalibWarning):
    """The observation matrix is close to rank deficient."""


class DataWarning(DoeCalibWarning):
    """Input accepted as it is, but worth a look (e.g. a joint reading a hair past its limit)."""


class PlausibilityWarning(DataWarning):
    """A fit that ran but looks implausible (σ̂/σ far from 1, units, huge placement errors)."""


class MisfitWarning(PlausibilityWarning):
    """The χ² test rejects a fit clearly: the residual is larger than the σ given explains
    (an effect the model lacks, or σ too small); ``doe-calib diagnose`` finds which."""


class ConvergenceWarning(DoeCalibWarning):
    """An iterative solver stopped before it converged."""


class CompilationWarning(DoeCalibWarning):
    """A Function could not be compiled; the slower CasADi virtual machine is used."""
