"""``load``: any JSON file the toolkit writes, read back by its ``format`` key.

The one module that knows every result type, so it sits above the layers (no result
and no reader in a layer imports it). Each format's reader is imported only when a file
of that format is read, and none builds a model: reading needs no CasADi and no user
effect file.
"""
from __future__ import annotations

from pathlib import Path

from doe_calib.errors import DataError
from doe_calib.io.json_file import read_json


def _identification(d, path):
    from doe_calib.estimation.result import IdentificationResult

    return IdentificationResult.from_dict(d)


def _parameters(d, path):
    from doe_calib.model.parameters import ParameterSet

    return ParameterSet.from_rows(d["parameters"])


def _design(d, path):
    from doe_calib.design.result import DesignResult

    return DesignResult.from_dict(d)


def _augment(d, path):
    from doe_calib.design.augment_result import AugmentResult

    return AugmentResult.from_dict(d)


def _diagnosis(d, path):
    from doe_calib.diagnosis.result import DiagnosisResult

    return DiagnosisResult.from_dict(d)


def _compensation(d, path):
    from doe_calib.compensation.result import CompensationResult

    return CompensationResult.from_dict(d)


def _comparison(d, path):
    from doe_calib.design.comparison import Comparison

    return Comparison.from_dict(d)


def _refine(d, path):
    """A refine history; its ``fit`` is the identification result written beside it
    (``X.json`` for ``X_refine.json``, as ``doe-calib refine`` names them), else None."""
    from dataclasses import replace

    from doe_calib.diagnosis.refine_result import RefineResult

    history = RefineResult.from_dict(d)
    path = Path(path)
    beside = path.with_name(path.name.removesuffix("_refine.json") + ".json")
    if path.name.endswith("_refine.json") and beside.exists():
        doc = read_json(beside, what="identification result")
        if doc.get("format") == "doe_calib.identification" and \
                doc.get("model") == d.get("final_model"):
            history = replace(history, fit=_identification(doc, beside))
    return history


#: ``format`` key → reader(dict, path).
READERS = {
    "doe_calib.identification": _identification,
    "doe_calib.parameters": _parameters,
    "doe_calib.design": _design,
    "doe_calib.augment": _augment,
    "doe_calib.diagnosis": _diagnosis,
    "doe_calib.refine": _refine,
    "doe_calib.comparison": _comparison,
    "doe_calib.compensation": _compensation,
}


def load(path):
    """Read any JSON file doe_calib writes, by its ``"format"`` key.

    Parameters
    ----------
    path : str or Path

    Returns
    -------
    object
        ``IdentificationResult``, ``ParameterSet``, ``DesignResult``,
        ``AugmentResult`` (``design --augment``), ``DiagnosisResult``, ``RefineResult``,
        ``Comparison`` or ``CompensationResult``, by the file's format
        (``doe_calib.identification``, ``.parameters``, ``.design``, ``.augment``,
        ``.diagnosis``, ``.refine``, ``.comparison``, ``.compensation``).

    Raises
    ------
    DataError
        Not JSON, an unknown format (the message lists the known ones), or a
        file of a known format that lacks what it should hold.

    Examples
    --------
    >>> result = doe_calib.load("result.json")  # doctest: +SKIP
    >>> result["dq_a2"]                         # doctest: +SKIP
    """
    d = read_json(path, what="doe_calib JSON file")
    kind = d.get("format") if isinstance(d, dict) else None
    reader = READERS.get(kind)
    if reader is None:
        raise DataError(f"unknown format {kind!r}; doe_calib.load reads the formats "
                        f"{', '.join(READERS)}", path, 1, 1)
    try:
        return reader(d, path)
    except DataError:
        raise
    except (KeyError, TypeError, ValueError) as exc:
        raise DataError(f"a {kind} file, but it lacks or has a wrong {exc}", path) from None
