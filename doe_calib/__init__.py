"""doe_calib: calibration of serial robots from multi-marker tracker measurements.

The data flow one way::

    URDF → Robot → effects → Model (CasADi) → observation matrix
         → {identify, predict_covariance, design} → results

Public API (SI units inside: m, rad, N, N·m; files in mm and deg):

>>> from doe_calib import Robot, Tool, build_model, example
>>> model = build_model(Robot.from_urdf(example.ROBOT_URDF), Tool.from_yaml(example.TOOL_YAML))
"""
from . import example
from .covariance import CovariancePrediction, point_covariance, predict_covariance
from .data import Configurations, Measurements
from .effects import DEFAULT_MODEL, REGISTRY
from .errors import (CollisionError, ConditioningWarning, ConvergenceWarning, DataError,
                     DoeCalibError, IdentifiabilityWarning, ModelError, OptionError,
                     SolverError)
from .evaluation import marker_positions, observation_matrix
from .identify import identify
from .measurement import Model, ModelDescription, build_model, describe_model, for_workload
from .parameters import Parameter, ParameterSet
from .results import IdentificationResult
from .robot import Robot
from .simulate import simulate
from .tool import Tool

__version__ = "0.1.0"

__all__ = [
    "Robot", "Tool", "Model", "ModelDescription", "build_model", "describe_model",
    "for_workload", "Parameter", "ParameterSet", "Configurations",
    "Measurements", "marker_positions", "observation_matrix", "identify",
    "IdentificationResult", "predict_covariance", "point_covariance", "CovariancePrediction",
    "simulate", "example", "DEFAULT_MODEL", "REGISTRY", "DoeCalibError", "DataError",
    "ModelError", "OptionError", "SolverError", "CollisionError", "IdentifiabilityWarning",
    "ConditioningWarning", "ConvergenceWarning",
]
