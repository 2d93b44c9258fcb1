"""A package's public names imported from their modules on first use (PEP 562).

A package whose ``__init__`` imports every module makes each command pay for
the ones it never uses (matplotlib's 3-D toolkit for a diagnosis figure, the
design solvers for a detectability). :func:`lazy_exports` gives a package the
module-level ``__getattr__`` and ``__dir__`` that import a name's module only
when the name is first asked for.
"""
from __future__ import annotations

import importlib


def lazy_exports(package: str, homes: dict, names) -> tuple:
    """``(__getattr__, __dir__)`` for ``package``: each name of ``homes`` (name → module
    of the package that defines it) imported on first use; ``names`` is the package's
    own ``globals()`` (what ``dir`` lists besides)."""

    def __getattr__(name: str):
        if name in homes:
            return getattr(importlib.import_module(f"{package}.{homes[name]}"), name)
        raise AttributeError(f"module {package!r} has no attribute {name!r}")

    def __dir__():
        return sorted({*names, *homes})

    return __getattr__, __dir__
