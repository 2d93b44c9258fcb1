"""Experiment design: choose the measurement poses that make the parameters most precise.

Per-candidate information blocks (:mod:`.problem`), the criterion objects
D, A, E and task (:mod:`.criteria`: ``criterion("D")``), the constraints on
a pose (:mod:`.constraints`, read from a file by :mod:`.constraint_file`, evaluated by
:mod:`.feasibility` on candidates drawn by :mod:`.candidates`), the convex
relaxation with its certified bound (:mod:`.relaxation`), the exact N-pose
exchange (:mod:`.exchange`, :mod:`.updates`), the continuous IPOPT
refinement (:mod:`.pose_refinement`, on the expressions of :mod:`.symbolic`)
— three solvers that each return a :class:`.outcome.DesignOutcome` — and the
pipeline (:mod:`.optimal`) behind ``doe-calib design`` with its result
(:mod:`.result`, predicted std by name from :mod:`.predicted_std`). A design
to discover effects (:mod:`.discovery`) chooses load cases (:mod:`.load_directions`)
and approach sides per pose (:mod:`.discovery_candidates`) by a constrained
exchange (:mod:`.constrained_exchange`).
"""
from doe_calib.runtime.lazy_exports import lazy_exports

#: Public name → the module of this package that defines it. Each is imported on first
#: use, so that a diagnosis's detectability (:mod:`.detectability`) does not load the
#: solvers, the criteria and CasADi's design expressions first.
_HOMES = {"read_constraints": "constraint_file", "Box": "constraints", "Coverage": "constraints",
          "DesignConstraints": "constraints", "LineOfSight": "constraints",
          "CRITERIA": "criteria", "AOptimal": "criteria", "Criterion": "criteria",
          "DOptimal": "criteria", "EOptimal": "criteria", "TaskOptimal": "criteria",
          "criterion": "criteria", "d_efficiency": "criteria", "efficiency": "criteria",
          "evaluate_criterion": "criteria", "log_det": "criteria", "exact_d_design": "exchange",
          "exact_design": "exchange", "LoadCase": "problem", "blocks_for": "problem",
          "design_parameters": "problem", "load_configurations": "problem",
          "task_matrix": "problem", "DesignOutcome": "outcome", "PredictedStd": "predicted_std",
          "StdMapping": "predicted_std", "convex_relaxation": "relaxation",
          "equivalence_ratio": "relaxation", "information": "relaxation", "relax": "relaxation",
          "relax_d": "relaxation", "variances": "relaxation"}

__all__ = list(_HOMES)


__getattr__, __dir__ = lazy_exports(__name__, _HOMES, globals())
