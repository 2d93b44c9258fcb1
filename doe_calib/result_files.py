"""``load``: any JSON file the toolkit writes, read back by its ``format`` key.

The one module that knows every result type, so it sits above the layers (no result
and no reader in a layer imports it). Each format's reader is imported only when a file
of that format is read, and none builds a model: reading needs no CasADi and no user
effect file.
"""
from __future__ import annotations

from importlib import import_module
from pathlib import Path

from doe_calib.errors import DataError
from doe_calib.io.json_file import read_json


def _from_dict(module: str, name: str):
    """The reader of a format whose class rebuilds itself: ``module.name.from_dict``."""
    return lambda d, path: getattr(import_module(module), name).from_dict(d)


def _parameters(d, path):
    from doe_calib.model.parameters import ParameterSet

    return ParameterSet.from_rows(d["parameters"])


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
            history = replace(history, fit=READERS["doe_calib.identification"](doc, beside))
    return history


#: ``format`` key → reader(dict, path).
READERS = {
    "doe_calib.identification": _from_dict("doe_calib.estimation.result",
                                           "IdentificationResult"),
    "doe_calib.parameters": _parameters,
    "doe_calib.design": _from_dict("doe_calib.design.result", "DesignResult"),
    "doe_calib.augment": _from_dict("doe_calib.design.augment_result", "AugmentResult"),
    "doe_calib.diagnosis": _from_dict("doe_calib.diagnosis.result", "DiagnosisResult"),
    "doe_calib.refine": _refine,
    "doe_calib.comparison": _from_dict("doe_calib.design.comparison", "Comparison"),
    "doe_calib.compensation": _from_dict("doe_calib.compensation.result", "CompensationResult"),
}


def load(path):
    """Read any JSON file doe_calib writes, by its ``"format"`` key.

    Parameters
    ----------
    path : str or Path

    Returns
    -------
    object
        By the file's format (a key of :data:`READERS`): ``IdentificationResult``,
        ``ParameterSet``, ``DesignResult``, ``AugmentResult`` (``design --augment``),
        ``DiagnosisResult``, ``RefineResult``, ``Comparison`` or ``CompensationResult``.

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
