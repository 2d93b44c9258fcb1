"""doe_calib: calibration of serial robots from multi-marker tracker measurements.

The data flow one way::

    URDF → Robot → effects → Model (CasADi) → observation matrix
         → {identify, predict_covariance, design} → results

Public API (SI units inside: m, rad, N, N·m; files in mm and deg):

>>> from doe_calib import Robot, Tool, build_model, examples
>>> model = build_model(Robot.from_urdf(examples.ROBOT_URDF), Tool.from_yaml(examples.TOOL_YAML))

Every public name is imported from its layer on first use (``doe_calib.X``
costs only what ``X`` needs); ``__all__`` lists them and docs/api/index.md
says where each lives.
"""
from importlib import import_module

__version__ = "0.1.0"

#: Public name → the module that defines it.
_PUBLIC = {
    # model
    "Robot": "doe_calib.model.robot",
    "Tool": "doe_calib.model.tool",
    "Parameter": "doe_calib.model.parameters",
    "ParameterSet": "doe_calib.model.parameters",
    "Model": "doe_calib.model.marker_model",
    "ModelDescription": "doe_calib.model.marker_model",
    "build_model": "doe_calib.model.marker_model",
    "describe_model": "doe_calib.model.marker_model",
    "for_workload": "doe_calib.model.marker_model",
    "marker_positions": "doe_calib.model.evaluation",
    "observation_matrix": "doe_calib.model.evaluation",
    "simulate": "doe_calib.model.simulate",
    "DEFAULT_MODEL": "doe_calib.model.effects",
    "REGISTRY": "doe_calib.model.effects",
    "DEFAULT_REGISTRY": "doe_calib.model.effects",
    "EffectRegistry": "doe_calib.model.effects.registry",
    "registry_with_files": "doe_calib.model.effects",
    "load_effect_file": "doe_calib.model.effects.user",
    # io
    "Configurations": "doe_calib.io.measurements",
    "Measurements": "doe_calib.io.measurements",
    "read_measurements": "doe_calib.io.csv_files",
    "write_measurements": "doe_calib.io.csv_files",
    "read_design": "doe_calib.io.csv_files",
    "load": "doe_calib.result_files",
    # estimation
    "identify": "doe_calib.estimation.identify",
    "FitSettings": "doe_calib.estimation.identify",
    "IdentificationResult": "doe_calib.estimation.result",
    "ParameterEstimate": "doe_calib.estimation.parameter_estimate",
    "FitStatistics": "doe_calib.estimation.fit_statistics",
    "Prediction": "doe_calib.estimation.predict",
    "predict": "doe_calib.estimation.predict",
    "predict_covariance": "doe_calib.estimation.covariance",
    "resolve_sigma": "doe_calib.estimation.sigma",
    "SettledSigma": "doe_calib.estimation.sigma",
    "point_covariance": "doe_calib.estimation.covariance",
    "CovariancePrediction": "doe_calib.estimation.covariance",
    # design
    "LoadCase": "doe_calib.design.problem",
    "read_constraints": "doe_calib.design.candidates.constraint_file",
    "optimal_design": "doe_calib.design.optimal",
    "DesignResult": "doe_calib.design.result",
    "Criterion": "doe_calib.design.criteria",
    "criterion": "doe_calib.design.criteria",
    "compare": "doe_calib.design.comparison",
    "Comparison": "doe_calib.design.comparison",
    # diagnosis
    "diagnose": "doe_calib.diagnosis.diagnose",
    "DiagnosisSettings": "doe_calib.diagnosis.settings",
    "RefineSettings": "doe_calib.diagnosis.settings",
    "DiagnosisResult": "doe_calib.diagnosis.result",
    "refine": "doe_calib.diagnosis.refine",
    "RefineResult": "doe_calib.diagnosis.refine_result",
    # compensation and export
    "compensate": "doe_calib.compensation.compensate",
    "CompensationResult": "doe_calib.compensation.result",
    "read_targets": "doe_calib.compensation.targets",
    "export_design": "doe_calib.export",
    "calibrated_urdf": "doe_calib.export.calibrated_urdf",
    # errors and warnings
    "DoeCalibError": "doe_calib.errors",
    "DoeCalibWarning": "doe_calib.errors",
    "DataError": "doe_calib.errors",
    "ModelError": "doe_calib.errors",
    "OptionError": "doe_calib.errors",
    "SolverError": "doe_calib.errors",
    "CollisionError": "doe_calib.errors",
    "IdentifiabilityWarning": "doe_calib.errors",
    "ConditioningWarning": "doe_calib.errors",
    "ConvergenceWarning": "doe_calib.errors",
    "DataWarning": "doe_calib.errors",
    "PlausibilityWarning": "doe_calib.errors",
    "MisfitWarning": "doe_calib.errors",
}

__all__ = sorted(_PUBLIC) + ["examples"]


def __getattr__(name: str):
    if name == "examples":
        return import_module("doe_calib.examples")
    try:
        module = _PUBLIC[name]
    except KeyError:
        raise AttributeError(f"module 'doe_calib' has no attribute {name!r}") from None
    value = getattr(import_module(module), name)
    globals()[name] = value  # looked up once
    return value


def __dir__():
    return __all__


# A result shows as its report in a notebook: the report gives each result type its view.
import_module("doe_calib.report.notebook").watch()
