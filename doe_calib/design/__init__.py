"""Experiment design: choose the measurement poses that make the parameters most precise.

This package holds the numerical core (issue 4, first part): per-candidate
information blocks (:mod:`.problem`), criteria (:mod:`.criteria`), the convex
relaxation with its certified bound (:mod:`.relaxation`) and the exact
N-pose exchange (:mod:`.exchange`), the pipeline (:mod:`.optimal`) behind
``doe-calib design`` and its result (:mod:`.result`). Constraints beyond joint
limits, the A/E/task criteria in the pipeline, the continuous IPOPT
refinement and the exports are not written yet.
"""
from .criteria import CRITERIA, d_efficiency, evaluate_criterion, log_det
from .exchange import exact_d_design
from .problem import LoadCase, blocks_for, design_parameters, load_configurations
from .relaxation import Relaxation, information, relax_d, variances

__all__ = ["CRITERIA", "d_efficiency", "evaluate_criterion", "log_det", "exact_d_design",
           "LoadCase", "blocks_for", "design_parameters", "load_configurations", "Relaxation",
           "information", "relax_d", "variances"]
