"""Experiment design: choose the measurement poses that make the parameters most precise.

Per-candidate information blocks (:mod:`.problem`), criteria D, A, E and
task (:mod:`.criteria`), the constraints on a pose (:mod:`.constraints`,
read from a file by :mod:`.constraint_file`, evaluated by
:mod:`.feasibility` on candidates drawn by :mod:`.candidates`), the convex
relaxation with its certified bound (:mod:`.relaxation`), the exact N-pose
exchange (:mod:`.exchange`, :mod:`.updates`), the continuous IPOPT
refinement (:mod:`.refine`, on the expressions of :mod:`.symbolic`), and the
pipeline (:mod:`.optimal`) behind ``doe-calib design`` with its result
(:mod:`.result`).
"""
from doe_calib.design.constraint_file import read_constraints
from doe_calib.design.constraints import Box, Coverage, DesignConstraints, LineOfSight
from doe_calib.design.criteria import (
           CRITERIA,
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
from doe_calib.design.relaxation import (
           Relaxation,
           equivalence_ratio,
           information,
           relax,
           relax_d,
           variances,
)

__all__ = ["read_constraints", "Box", "Coverage", "DesignConstraints", "LineOfSight", "CRITERIA",
           "d_efficiency", "efficiency", "evaluate_criterion", "log_det", "exact_d_design",
           "exact_design", "LoadCase", "blocks_for", "design_parameters", "load_configurations",
           "task_matrix", "Relaxation", "equivalence_ratio", "information", "relax", "relax_d",
           "variances"]
