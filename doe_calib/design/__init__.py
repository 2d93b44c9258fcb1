"""Experiment design: choose the measurement poses that make the parameters most precise.

One pipeline (:mod:`.pipeline`) runs every design: candidates → information →
relaxation → exchange (reachable from home) → refinement → bound → assessment.
The goals that plug into it: a criterion of the poses' information
(:mod:`.optimal`, the criteria D, A, E and task of :mod:`.criteria`), a design
that can discover effects (:mod:`.discovery`), the poses that add most to a
measured campaign (:mod:`.augment`) and the socket contacts to seat, plane
touches to make or ballbar positions to read without a tracker
(:mod:`.contacts`, its result :mod:`.contact_result`). The candidates and what
they must satisfy live in :mod:`.candidates`, the solvers in :mod:`.solvers`; the information
blocks in :mod:`.problem`; the results in :mod:`.result` (predicted std by name
from :mod:`.predicted_std`) and :mod:`.augment_result`; :mod:`.comparison` sets
designs and identification results side by side.
"""
from doe_calib.runtime.lazy_exports import lazy_exports

#: Public name → the module of this package that defines it. Each is imported on first
#: use, so that a diagnosis's detectability (:mod:`.detectability`) does not load the
#: solvers, the criteria and CasADi's design expressions first.
_HOMES = {"read_constraints": "candidates.constraint_file",
          "DesignConstraints": "candidates.constraints", "LineOfSight": "candidates.constraints",
          "CRITERIA": "criteria", "AOptimal": "criteria", "Criterion": "criteria",
          "DOptimal": "criteria", "EOptimal": "criteria", "TaskOptimal": "criteria",
          "criterion": "criteria", "efficiency": "criteria", "log_det": "criteria",
          "exact_design": "solvers.exchange", "LoadCase": "problem", "blocks_for": "problem",
          "design_parameters": "problem", "load_configurations": "problem",
          "convex_relaxation": "solvers.relaxation", "information": "solvers.relaxation",
          "relax": "solvers.relaxation", "variances": "solvers.relaxation"}

__all__ = list(_HOMES)


__getattr__, __dir__ = lazy_exports(__name__, _HOMES, globals())
