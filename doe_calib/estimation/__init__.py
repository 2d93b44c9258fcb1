"""Estimation: the estimators (point, two-step, pose), identifiability, covariance,
plausibility, prediction and the identification result."""
