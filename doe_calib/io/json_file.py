"""JSON files of the toolkit (results, designs, parameters): one reader, one writer."""
from __future__ import annotations

import json
import math

from doe_calib.errors import DataError


def write_json(data: dict, path=None) -> str:
    """JSON text of ``data`` (UTF-8, indented); also written to ``path`` when given."""
    text = json.dumps(data, indent=1, ensure_ascii=False)
    if path is not None:
        with open(path, "w", encoding="utf-8") as fh:
            fh.write(text)
    return text


def _finite(data):
    """``data`` with every non-finite float (NaN, ±inf) replaced by None."""
    if isinstance(data, float):
        return data if math.isfinite(data) else None
    if isinstance(data, dict):
        return {k: _finite(v) for k, v in data.items()}
    if isinstance(data, (list, tuple)):
        return [_finite(v) for v in data]
    return data


def strict_json(data) -> str:
    """Strict JSON text of ``data`` for other programs: NaN and ±inf become ``null``.

    Examples
    --------
    >>> json.loads(strict_json({"p": float("nan"), "q": [1.5, float("-inf")]}))
    {'p': None, 'q': [1.5, None]}
    """
    return json.dumps(_finite(data), indent=1, ensure_ascii=False, allow_nan=False)


def read_json(path, kind: str | None = None, what: str = "file") -> dict:
    """Read a JSON file; errors name the file, line and column.

    ``kind``, when given, is the required value of the file's ``format`` key.
    """
    try:
        with open(path, encoding="utf-8") as fh:
            data = json.load(fh)
    except json.JSONDecodeError as exc:
        raise DataError(f"not valid JSON: {exc.msg}", path, exc.lineno, exc.colno) from exc
    except OSError as exc:
        raise DataError(f"cannot read the {what}: {exc.strerror}", path) from exc
    if kind is not None and (not isinstance(data, dict) or data.get("format") != kind):
        raise DataError(f"not a {what} (expected \"format\": \"{kind}\")", path, 1, 1)
    return data
