"""Model diagnosis: where the model fails, which physical effect is missing, and adding it.

>>> from doe_calib.diagnosis import diagnose   # doctest: +SKIP
>>> print(diagnose(model, measurements).summary())   # doctest: +SKIP
"""
from doe_calib.diagnosis.candidate import Candidate, FittedSize
from doe_calib.diagnosis.cross_validation import validation_rms
from doe_calib.diagnosis.effect_tests import candidate_effects
from doe_calib.diagnosis.diagnose import diagnose
from doe_calib.diagnosis.result import DiagnosisResult

__all__ = ["diagnose", "DiagnosisResult", "Candidate", "FittedSize", "candidate_effects",
           "validation_rms"]
