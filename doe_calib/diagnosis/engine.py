"""``diagnose``: from a fitted model and its data to a ranked list of missing effects, in words."""
from __future__ import annotations


import numpy as np
from scipy import stats

from ..errors import DoeCalibError
from ..effects import parse_effect
from ..identify import identify_quietly
from .candidates import augmented, test_candidates
from .cross_validation import cross_validated_rms
from .residuals import adequacy, flagged_poses, repeatability_sigma, residuals
from .result import DiagnosisResult
from .variables import configuration_variables, follows

_PHRASES = {"cyclic": "a cyclic (transmission) error of joint {j}",
            "gear_ratio": "a gear-ratio (encoder scale) error of joint {j}",
            "backlash": "backlash of joint {j}",
            "compliance_by_angle": "a compliance of joint {j} that changes with its angle",
            "joint_offset": "joint offsets", "geometry": "link geometry errors",
            "joint_compliance": "joint compliance", "thermal": "thermal expansion of the links",
            "link_compliance": "bending of the links under load"}


def describe(candidate, robot) -> str:
    """The candidate in words, e.g. "a cyclic (transmission) error of joint 3 (a3)"."""
    j = "" if candidate.joint is None else \
        f"{candidate.joint} ({robot.joints[candidate.joint - 1].name})"
    return _PHRASES.get(candidate.effect, f"effect {candidate.spec}").format(j=j)


def _proposal(adequate_test, tests, level):
    """The best significant candidate if it explains the residual, and the χ² p left after it.

    It explains the residual when it accounts for at least half of it, or
    when the model with it would pass the adequacy test.
    """
    best = next((t for t in tests if t.p_value < level), None)
    remaining_p = 1.0 if best is None else float(stats.chi2.sf(
        adequate_test.statistic * (1 - best.explained_fraction), adequate_test.dof - best.rank))
    if best is not None and (best.explained_fraction >= 0.5 or remaining_p >= level):
        return best, remaining_p
    return None, remaining_p


def _verdict(model, adequate_test, cv_rms, noise, tests, follow, flagged, level):
    sig = [t for t in tests if t.p_value < level]
    floor = f"noise floor {noise:.3g} mm"
    if adequate_test.adequate and not sig:
        return (f"The model is adequate: residuals are consistent with the noise "
                f"(χ² p = {adequate_test.p_value:.2g}, cross-validated RMS {cv_rms:.3g} mm, "
                f"{floor}); no catalogue effect is significant at the {level:.0%} level.")
    lead = ""
    if follow:
        top = follow[0]
        lead = f"Residuals follow {top.variable} (adjusted R² {top.r2:.2f}). "
    proposed, remaining_p = _proposal(adequate_test, tests, level)
    best = sig[0] if sig else None
    if proposed is not None:
        best = proposed
        words = describe(best, model.robot)
        text = (f"{lead}{words[0].upper()}{words[1:]} explains "
                f"{100 * best.explained_fraction:.0f} % of the remaining variance "
                f"(F = {best.statistic:.3g}, p = {best.p_value:.2g})")
        if best.cv_rms_mm is not None:
            text += (f"; adding it ({best.spec}) moves the cross-validated RMS from "
                     f"{cv_rms:.3g} to {best.cv_rms_mm:.3g} mm ({floor})")
        if remaining_p < level:
            text += (". Even with it the residual would stay above the noise: look at the "
                     "variables below as well")
        if adequate_test.adequate:
            text = "The residual is within the noise overall, but: " + text
        return text + "."
    names = ", ".join(f"{f.variable} (R² {f.r2:.2f})" for f in follow[:3]) or "no variable"
    where = ", ".join(p["pose"] for p in flagged[:5])
    partly = "" if best is None else (
        f" (the best, {best.spec}, is significant but explains only "
        f"{100 * best.explained_fraction:.0f} % of it)")
    return (f"The model is NOT adequate (χ² p = {adequate_test.p_value:.2g}, residual "
            f"σ̂ = {adequate_test.sigma_hat_mm:.3g} mm against {floor}) and no catalogue effect "
            f"explains it{partly}. The residual size follows {names}"
            + (f"; the largest residuals are at poses {where}" if where else "")
            + ". Write a custom effect in those variables (--effect-file).")


def diagnose(model, measurements, fit=None, level: float = 0.01, folds: int = 5,
             cv_top: int = 6, progress=None) -> DiagnosisResult:
    """Diagnose ``model`` on ``measurements``.

    Parameters
    ----------
    model : Model
    measurements : Measurements
        Readings with their σ (m).
    fit : IdentificationResult, optional
        The model's fit to these data; identified here when not given.
    level : float
        Significance level for the adequacy test and for proposing an effect.
    folds : int
        Folds (by pose) of the cross-validation.
    cv_top : int
        Cross-validate this many of the significant candidates with the smallest p;
        those are then ranked by cross-validated RMS.
    progress : callable, optional
        ``progress(done, total, note)`` while candidates are cross-validated.

    Returns
    -------
    DiagnosisResult
    """
    if fit is None:
        fit = identify_quietly(model, measurements)
    params = fit.parameters
    res = residuals(model, measurements, params.values)
    rank = int(params.free.sum())
    rep = repeatability_sigma(measurements)
    sigma_mm = float(np.median(measurements.sigma) * 1e3)
    test = adequacy(res, rank, sigma_mm, level, rep)
    cv = cross_validated_rms(model, measurements, params, folds)
    tests = test_candidates(model, measurements, params)
    chosen = [t for t in tests if t.p_value < level][:cv_top]
    scored = {}
    for i, t in enumerate(chosen):
        if progress:
            progress(i, len(chosen), t.spec)
        big, bp = augmented(model, params, parse_effect(t.spec))
        try:  # folds start from the grown model's own fit: what they hold fixed is then right
            bp = identify_quietly(big, measurements, bp, register=False).parameters
        except DoeCalibError:
            scored[t.spec] = t.with_cv(float("nan"))
            continue
        scored[t.spec] = t.with_cv(cross_validated_rms(big, measurements, bp, folds))
    ranked = sorted(scored.values(), key=lambda t: (np.nan_to_num(t.cv_rms_mm, nan=np.inf),
                                                     t.log10_p))
    ranked += [t for t in tests if t.spec not in scored]
    size = np.bincount(res.config, (res.weighted ** 2).sum(axis=1),
                       minlength=len(measurements.configurations))
    count = np.bincount(res.config, minlength=len(measurements.configurations)) * 3
    used = count > 0
    variables = {k: (v[0][used], v[1], v[2]) for k, v in
                 configuration_variables(model.robot, measurements.configurations).items()}
    follow = follows(size[used] / count[used], variables)
    flagged = flagged_poses(res, test.dof / res.weighted.size)
    verdict = _verdict(model, test, cv, test.sigma_mm, ranked, follow, flagged, level)
    proposed, _ = _proposal(test, ranked, level)
    chi2 = {"statistic": test.statistic, "dof": test.dof, "p_value": test.p_value,
            "sigma_source": test.sigma_source, "sigma_hat_mm": test.sigma_hat_mm}
    return DiagnosisResult(model.spec, res.rms_mm, cv, test.sigma_mm, test.adequate, chi2,
                           tuple(ranked), tuple(follow), tuple(flagged), level, verdict,
                           None if proposed is None else proposed.spec, int(res.weighted.size))
