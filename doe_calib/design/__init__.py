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
from doe_calib.design.constraint_file import read_constraints
from doe_calib.design.constraints import Box, Coverage, DesignConstraints, LineOfSight
from doe_calib.design.criteria import (
           CRITERIA,
           AOptimal,
           Criterion,
           DOptimal,
           EOptimal,
           TaskOptimal,
           criterion,
           d_efficiency,
           efficiency,
           evaluate_criterion,
           log_det,
)
from doe_calib.design.exchange import exact_d_design, exact_design
from doe_calib.design.problem import (
           LoadCase,
           blocks_for,
           design_parameters,
           load_configurations,
           task_matrix,
)
from doe_calib.design.outcome import DesignOutcome
from doe_calib.design.predicted_std import PredictedStd, StdMapping
from doe_calib.design.relaxation import (
           convex_relaxation,
           equivalence_ratio,
           information,
           relax,
           relax_d,
           variances,
)

__all__ = ["read_constraints", "Box", "Coverage", "DesignConstraints", "LineOfSight", "CRITERIA",
           "AOptimal", "Criterion", "DOptimal", "EOptimal", "TaskOptimal", "criterion",
           "d_efficiency", "efficiency", "evaluate_criterion", "log_det", "exact_d_design",
           "exact_design", "LoadCase", "blocks_for", "design_parameters", "load_configurations",
           "task_matrix", "DesignOutcome", "PredictedStd", "StdMapping", "convex_relaxation",
           "equivalence_ratio", "information", "relax", "relax_d",
           "variances"]
