"""Experiment design: choose the measurement poses that make the parameters most precise.

This package holds the numerical core (issue 4, first part): per-candidate
information blocks (:mod:`.problem`), criteria (:mod:`.criteria`), the convex
relaxation with its certified bound (:mod:`.relaxation`) and the exact
N-pose exchange (:mod:`.exchange`). Constraints beyond joint limits, the
continuous IPOPT refinement, the ``doe-calib design`` command and exports
are not written yet.
"""
from .criteria import CRITERIA, d_efficiency, evaluate_criterion, log_det
from .exchange import exact_d_design
from .problem import LoadCase, blocks_for, design_parameters, load_configurations
from .relaxation import Relaxation, information, relax_d, variances

__all__ = ["CRITERIA", "d_efficiency", "evaluate_criterion", "log_det", "exact_d_design",
           "LoadCase", "blocks_for", "design_parameters", "load_configurations", "Relaxation",
           "information", "relax_d", "variances"]
