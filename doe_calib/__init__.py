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

#: Module → the public names it defines.
_NAMES = {
    "doe_calib.model.robot": ("Robot",),
    "doe_calib.model.tool": ("Tool",),
    "doe_calib.model.parameters": ("Parameter", "ParameterSet"),
    "doe_calib.model.marker_model": ("Model", "ModelDescription", "build_model", "describe_model",
                                     "for_workload"),
    "doe_calib.model.evaluation": ("marker_positions", "observation_matrix"),
    "doe_calib.model.simulate": ("simulate",),
    "doe_calib.model.effects": ("DEFAULT_MODEL", "REGISTRY", "DEFAULT_REGISTRY",
                                "registry_with_files"),
    "doe_calib.model.effects.registry": ("EffectRegistry",),
    "doe_calib.model.effects.user": ("load_effect_file",),
    "doe_calib.io.measurements": ("Configurations", "Measurements"),
    "doe_calib.io.csv_files": ("read_measurements", "write_measurements", "read_design"),
    "doe_calib.result_files": ("load",),
    "doe_calib.estimation.identify": ("identify", "FitSettings"),
    "doe_calib.estimation.result": ("IdentificationResult",),
    "doe_calib.estimation.parameter_estimate": ("ParameterEstimate",),
    "doe_calib.estimation.fit_statistics": ("FitStatistics",),
    "doe_calib.estimation.predict": ("Prediction", "predict"),
    "doe_calib.estimation.covariance": ("predict_covariance", "point_covariance",
                                        "CovariancePrediction"),
    "doe_calib.estimation.sigma": ("resolve_sigma", "SettledSigma"),
    "doe_calib.design.problem": ("LoadCase",),
    "doe_calib.design.candidates.constraint_file": ("read_constraints",),
    "doe_calib.design.optimal": ("optimal_design",),
    "doe_calib.design.result": ("DesignResult",),
    "doe_calib.design.criteria": ("Criterion", "criterion"),
    "doe_calib.design.comparison": ("compare", "Comparison"),
    "doe_calib.diagnosis.diagnose": ("diagnose",),
    "doe_calib.diagnosis.settings": ("DiagnosisSettings", "RefineSettings"),
    "doe_calib.diagnosis.result": ("DiagnosisResult",),
    "doe_calib.diagnosis.refine": ("refine",),
    "doe_calib.diagnosis.refine_result": ("RefineResult",),
    "doe_calib.compensation.compensate": ("compensate",),
    "doe_calib.compensation.result": ("CompensationResult",),
    "doe_calib.compensation.targets": ("read_targets",),
    "doe_calib.export": ("export_design",),
    "doe_calib.export.calibrated_urdf": ("calibrated_urdf",),
    "doe_calib.errors": ("DoeCalibError", "DoeCalibWarning", "DataError", "ModelError",
                         "OptionError", "SolverError", "CollisionError", "IdentifiabilityWarning",
                         "ConditioningWarning", "ConvergenceWarning", "DataWarning",
                         "PlausibilityWarning", "MisfitWarning"),
}

#: Public name → the module that defines it.
_PUBLIC = {name: module for module, names in _NAMES.items() for name in names}

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
