"""The simulator that owes nothing to our effect modules, for the studies that judge on it."""
from __future__ import annotations

import importlib.util
import sys
from pathlib import Path


def independent_sim():
    """``tests/independent_sim.py`` (numpy + Pinocchio), as the module ``independent_sim``."""
    path = Path(__file__).resolve().parents[1] / "tests" / "independent_sim.py"
    spec = importlib.util.spec_from_file_location("independent_sim", path)
    module = importlib.util.module_from_spec(spec)
    sys.modules.setdefault(spec.name, module)
    spec.loader.exec_module(module)
    return module
