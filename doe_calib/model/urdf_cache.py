"""Chains read from URDF files, kept: reading a robot read before needs no Pinocchio.

Importing Pinocchio costs 0.2–0.3 s, half of a 60-pose ``doe-calib identify``.
:meth:`~doe_calib.model.robot.Robot.from_urdf` keeps each chain it reads
(:meth:`~doe_calib.model.robot.Robot.to_dict`, JSON) in the cache directory
(:func:`~doe_calib.model.compiled.cache_dir`, ``robots/``) under a key made of
the file's bytes, the flange asked for, the installed Pinocchio (its path and
modification time) and the reader's own source: the same bytes read again
give the stored chain, and any change to one of them reads the file anew. A
read that fails stores nothing; a damaged or unreadable entry is read anew; a
cache directory that cannot be written costs only the time.
"""
from __future__ import annotations

import hashlib
import importlib.util
import json
import os
import tempfile

from doe_calib.model.compiled import cache_dir

#: Bump when the stored form changes.
FORMAT = 1


def key(urdf: bytes, flange: str | None, reader: bytes) -> str:
    """The cache key of the chain read from ``urdf`` (the file's bytes) to ``flange`` by the
    reader whose source is ``reader``."""
    spec = importlib.util.find_spec("pinocchio")
    origin = spec.origin if spec is not None and spec.origin else ""
    stamp = os.stat(origin).st_mtime_ns if origin else 0
    h = hashlib.sha256()
    for part in (str(FORMAT).encode(), urdf, (flange or "").encode(), origin.encode(),
                 str(stamp).encode(), reader):
        h.update(len(part).to_bytes(8, "little"))
        h.update(part)
    return h.hexdigest()[:32]


def load(k: str) -> dict | None:
    """The chain stored under ``k`` (a :meth:`Robot.to_dict`), or None."""
    try:
        return json.loads((cache_dir() / "robots" / f"{k}.json").read_text(encoding="utf-8"))
    except (OSError, ValueError):
        return None


def store(k: str, chain: dict) -> None:
    """Keep ``chain`` under ``k`` (written whole or not at all)."""
    folder = cache_dir() / "robots"
    try:
        folder.mkdir(parents=True, exist_ok=True)
        fd, tmp = tempfile.mkstemp(dir=folder, suffix=".tmp")
        with os.fdopen(fd, "w", encoding="utf-8") as out:
            json.dump(chain, out)
        os.replace(tmp, folder / f"{k}.json")
    except OSError:
        pass
