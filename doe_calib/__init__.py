"""doe_calib: calibration of serial robots from multi-marker tracker measurements.

The data flow one way::

    URDF → Robot → effects → Model (CasADi) → observation matrix
         → {identify, predict_covariance, design} → results

Public API (SI units inside: m, rad, N, N·m; files in mm and deg):

>>> from doe_calib import Robot, Tool, build_model, examples
>>> model = build_model(Robot.from_urdf(examples.ROBOT_URDF), Tool.from_yaml(examples.TOOL_YAML))
"""
from doe_calib import examples
from doe_calib.errors import (
                     CollisionError,
                     ConditioningWarning,
                     ConvergenceWarning,
                     DataError,
                     DoeCalibError,
                     DoeCalibWarning,
                     IdentifiabilityWarning,
                     ModelError,
                     OptionError,
                     SolverError,
)
from doe_calib.estimation.covariance import (
                     CovariancePrediction,
                     point_covariance,
                     predict_covariance,
)
from doe_calib.estimation.identify import identify
from doe_calib.estimation.result import IdentificationResult
from doe_calib.estimation.sigma import SettledSigma, resolve_sigma
from doe_calib.io.measurements import Configurations, Measurements
from doe_calib.model.effects import DEFAULT_MODEL, REGISTRY
from doe_calib.model.evaluation import marker_positions, observation_matrix
from doe_calib.model.marker_model import (
                     Model,
                     ModelDescription,
                     build_model,
                     describe_model,
                     for_workload,
)
from doe_calib.model.parameters import Parameter, ParameterSet
from doe_calib.model.robot import Robot
from doe_calib.model.simulate import simulate
from doe_calib.model.tool import Tool

__version__ = "0.1.0"

__all__ = [
    "Robot", "Tool", "Model", "ModelDescription", "build_model", "describe_model",
    "for_workload", "Parameter", "ParameterSet", "Configurations",
    "Measurements", "marker_positions", "observation_matrix", "identify",
    "IdentificationResult", "predict_covariance", "point_covariance", "CovariancePrediction",
    "simulate", "examples", "DEFAULT_MODEL", "REGISTRY", "DoeCalibError", "DataError",
    "ModelError", "OptionError", "SolverError", "CollisionError", "IdentifiabilityWarning",
    "ConditioningWarning", "ConvergenceWarning",
    "DoeCalibWarning", "resolve_sigma", "SettledSigma",
]
