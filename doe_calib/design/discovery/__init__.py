"""Designs that can discover effects: the goal (:mod:`.goal`), the candidates as poses in
load cases and approach sides (:mod:`.variants`, the load cases from :mod:`.load_directions`),
what a campaign can reveal (:mod:`.detection`) and the refinement that keeps each pose's load
case (:mod:`.refinement`)."""
from doe_calib.runtime.lazy_exports import lazy_exports

#: The goal is imported on first use: its statistics load slowly.
_HOMES = {"DiscoveryGoal": "goal"}

__all__ = list(_HOMES)

__getattr__, __dir__ = lazy_exports(__name__, _HOMES, globals())
