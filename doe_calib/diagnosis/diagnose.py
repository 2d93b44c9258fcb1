"""``diagnose``: from a fitted model and its data to a ranked list of missing effects, in words.

An effect is proposed when it is significant (score test, Bonferroni over
every candidate and shape tried) and lowers the cross-validated RMS by a
material margin (``min_gain``); among those, the lowest cross-validated RMS
wins. Whether the model is adequate is a separate verdict: the χ² test of the
residual against σ, or, where that test is too sharp to be useful (large
N), no candidate making a material gain and either σ̂ within ``tolerance`` of σ
or the misfit beyond the noise, √(σ̂² − σ²), below a stated practical size
(``practical_um``).
"""
from __future__ import annotations

import numpy as np

from doe_calib.diagnosis.candidate import candidate_records, sizes_words
from doe_calib.diagnosis.candidate_scoring import score_candidates
from doe_calib.diagnosis.cross_validation import cross_validated_rms, make_folds
from doe_calib.diagnosis.effect_tests import candidate_tests
from doe_calib.diagnosis.outliers import gross_outliers, outlier_verdict
from doe_calib.diagnosis.residuals import adequacy, flagged_poses, residuals
from doe_calib.diagnosis.result import DiagnosisResult
from doe_calib.diagnosis.settings import DiagnosisSettings
from doe_calib.diagnosis.sign_lead import sign_lead
from doe_calib.diagnosis.variables import configuration_variables, follows
from doe_calib.design.detectability import SEPARATE
from doe_calib.errors import ModelError
from doe_calib.estimation.identify import identify_quietly
from doe_calib.estimation.load_units import kgf_finding
from doe_calib.estimation.sigma import resolve_sigma
from doe_calib.io.measurements import ESTIMATED, REPEATED
from doe_calib.io.repeated_readings import copies_words
from doe_calib.model.effects import parse_effect

#: A residual "follows" a variable when its adjusted R² reaches this.
FOLLOWS_R2 = 0.2

#: Candidates are tested and cross-validated on at most this many configurations.
SCREENING_CONFIGURATIONS = 1500


def screening_set(measurements, limit: int = SCREENING_CONFIGURATIONS, seed: int = 0):
    """The readings candidates are tested on: all, or whole poses drawn at random up to ``limit``
    configurations; and a note in words when it is a subset."""
    cfg = measurements.configurations
    if len(cfg) <= limit:
        return measurements, ""
    poses = np.array(list(dict.fromkeys(cfg.pose)))
    per_pose = len(cfg) / len(poses)
    keep = set(np.random.default_rng(seed).permutation(poses)[:int(limit / per_pose)])
    subset = measurements.subset(np.array([cfg.pose[c] in keep for c in measurements.config]))
    return subset, (f"candidate effects were tested and cross-validated on {len(keep)} poses "
                    f"drawn at random ({len(subset.configurations)} of {len(cfg)} "
                    f"configurations); the adequacy test and the fit use every reading")


def settled_fit(model, measurements, sigma=None, fit=None):
    """σ settled as on the command line (:func:`~doe_calib.estimation.sigma.resolve_sigma`,
    its ``.measurements`` the readings with it) and ``model``'s fit at that σ: ``fit`` when
    the readings already had it, else identified here."""
    settled = resolve_sigma(model, measurements, sigma, fit=fit)
    if fit is None or settled.measurements is not measurements:
        fit = identify_quietly(model, settled.measurements)
    return settled, fit


def describe(candidate, robot, registry=None) -> str:
    """The candidate in its effect's words (:meth:`Effect.describe`), e.g. "a cyclic
    (transmission) error of joint 3 (a3)"; ``registry`` names the effects (default the
    catalogue)."""
    try:
        return parse_effect(candidate.spec, registry=registry).describe(robot)
    except ModelError:
        return f"effect {candidate.spec}"


def _groups_to_try(tests, level, top):
    """Significant candidates of the ``top`` strongest (effect, joint) groups, every shape."""
    keys = list(dict.fromkeys((t.effect, t.joint) for t in tests if t.p_value < level))[:top]
    return [t for t in tests if t.p_value < level and (t.effect, t.joint) in keys]


def _material(tests, cv_rms, level, min_gain):
    """Significant candidates that lower the cross-validated RMS by ``min_gain``, best first.

    Cross-validated RMS equal to 9 significant digits are a tie (two shapes of one effect
    that these data cannot tell apart differ only by rounding): the order of ``tests``
    decides, the stronger test and then the catalogue's order (an effect's default shape
    first)."""
    return sorted([t for t in tests if t.p_value < level and t.cv_rms_mm is not None
                   and np.isfinite(t.cv_rms_mm) and t.cv_rms_mm < cv_rms * (1 - min_gain)],
                  key=_cv_key)


def _cv_key(t) -> float:
    """A candidate's cross-validated RMS to 9 significant digits (ties: module order)."""
    return float(f"{np.nan_to_num(t.cv_rms_mm, nan=np.inf):.9g}")


def _gross_errors(test, flagged, follow, n_poses):
    """Whether the misfit sits in a few poses that follow no variable."""
    excess = test.statistic - test.dof
    if not flagged or excess <= 0 or len(flagged) > max(1, 0.1 * n_poses):
        return False
    inside = sum(p["chi2"] - p["chi2"] / p["chi2_per_dof"] for p in flagged)
    return inside >= 0.5 * excess and (not follow or follow[0].r2 < FOLLOWS_R2)


def _adequacy_words(test):
    if test.sigma_source == ESTIMATED:
        return (f"σ̂/σ = {test.ratio:.3f} against σ̂ of the starting model's fit, "
                f"{test.sigma_mm:.3g} mm, as no σ was given")
    lo, hi = test.ratio_interval()
    source = "of repeated readings" if test.sigma_source == REPEATED else test.sigma_source
    return (f"σ̂/σ = {test.ratio:.3f} (95 % interval {lo:.3f}–{hi:.3f}; χ² p = "
            f"{test.p_value:.2g}, σ {source} {test.sigma_mm:.3g} mm); misfit beyond "
            f"the noise √(σ̂² − σ²) = {test.misfit_um:.3g} µm")


def _adequate_why(test, s) -> str:
    """Which rule found the model adequate, in words."""
    if test.adequate:
        return "consistent with the noise"
    if test.ratio <= 1 + s.tolerance:
        return f"within {s.tolerance:.0%} of the noise"
    return (f"{test.misfit_um:.3g} µm beyond the noise per coordinate, below the practical "
            f"size of {s.practical_um:g} µm (--practical-um): the χ² test at this N detects a "
            f"misfit too small to matter — second-order effects of parameters held at "
            f"nominal, or σ a few % optimistic")


def _is_adequate(test, proposed, s) -> bool:
    """Adequate by the module's rules; with no σ given (σ̂ holds the model's own misfit),
    only that no candidate helps."""
    if test.sigma_source == ESTIMATED:
        return proposed is None
    return test.adequate or (proposed is None and (test.ratio <= 1 + s.tolerance
                                                   or test.misfit_um < s.practical_um))


def _confounded_words(tests, proposed, level) -> str:
    """A sentence naming the significant candidates that the model's own parameters absorb
    (not said silently as "too small a gain")."""
    if proposed is not None:  # what the proposal explains is said with it
        return _rivals_words(tests, proposed, level)
    hidden = [t for t in tests if t.p_value < level and t.absorbed_by][:2]
    return "".join(
        f" {t.spec} is significant (p = {t.p_value:.2g}) but {100 * t.absorbed_fraction:.0f} % "
        f"of its signature is absorbed by the model: in these poses it cannot be told apart "
        f"from {', '.join(t.absorbed_by)} ({SEPARATE})." for t in hidden)


#: Candidates of other effects whose cross-validated RMS is within this fraction of the
#: proposed one's explain the data as well: these poses cannot tell them apart.
RIVAL_MARGIN = 0.005


def _rivals_words(tests, proposed, level) -> str:
    """A sentence naming other effects that predict as well as the proposed one."""
    best = proposed.cv_rms_mm
    rivals = [t for t in tests if t.p_value < level and t.cv_rms_mm is not None
              and np.isfinite(t.cv_rms_mm) and (t.effect, t.joint) != (proposed.effect,
                                                                       proposed.joint)
              and t.cv_rms_mm <= best * (1 + RIVAL_MARGIN)]
    if not rivals:
        return ""
    names = ", ".join(f"{t.spec} ({t.cv_rms_mm:.4g} mm)" for t in rivals[:3])
    return (f" These poses cannot tell {proposed.spec} ({best:.4g} mm) apart from {names}: "
            f"they predict equally well here; {SEPARATE.replace('them', 'the effects')}, "
            f"before either is trusted away from these poses.")


def _verdict_words(model, test, adequate, cv, folds, tests, proposed, follow, flagged, gross,
                   s, registry=None):
    ratio = _adequacy_words(test)
    cv_words = f"cross-validated RMS {cv:.3g} mm ({folds.description})"
    if proposed is not None:
        words = describe(proposed, model.robot, registry)
        size = sizes_words(proposed.sizes[:4])
        text = (f"{words[0].upper()}{words[1:]} is missing: adding {proposed.spec} lowers the "
                f"{cv_words} to {proposed.cv_rms_mm:.3g} mm "
                f"({100 * (1 - proposed.cv_rms_mm / cv):.0f} %) and accounts for "
                f"{100 * proposed.explained_fraction:.0f} % of the residual (F = "
                f"{proposed.statistic:.3g}, p = {proposed.p_value:.2g})")
        if size:
            text += f"; fitted {size}"
        if proposed.implausible:
            text += f" — {proposed.implausible}"
        if not adequate:
            text += (f". The model is not adequate yet ({ratio}): refine adds effects one at a "
                     f"time while they help")
        return text + "."
    if adequate and test.sigma_source == ESTIMATED:
        return (f"No candidate effect lowers the {cv_words} by {s.min_gain:.0%}: the model is "
                f"adequate as far as the candidates tell. σ was not given, so the residual is "
                f"not tested against the noise: σ̂ of the starting model's fit, "
                f"{test.sigma_mm:.3g} mm (σ̂/σ = {test.ratio:.3f} here), holds that model's "
                f"misfit; give σ (--sigma, a sigma column) or read some poses twice for that "
                f"test.")
    if adequate:
        why = _adequate_why(test, s)
        return (f"The model is adequate: the residual is {why} ({ratio}); no candidate effect "
                f"lowers the {cv_words} by {s.min_gain:.0%}.")
    where = ", ".join(p["pose"] + (f" (line {p['worst_line']})" if p["worst_line"] else "")
                      for p in flagged[:8])
    if gross:
        return (f"The model is NOT adequate ({ratio}), but the misfit sits in {len(flagged)} "
                f"pose(s) — {where} — and follows no measured variable: those readings look "
                f"like gross errors (a reading off its target, a swapped marker, a pose typed "
                f"wrong). Check them; to leave them out, rerun with --exclude-poses "
                f"{','.join(p['pose'] for p in flagged)} (each exclusion is reported).")
    sig = [t for t in tests if t.p_value < s.level]
    partly = "" if not sig else (f" ({len(sig)} candidates are significant, but none lowers the "
                                 f"{cv_words} by {s.min_gain:.0%})")
    strong = [f for f in follow if f.r2 >= FOLLOWS_R2]
    text = (f"The model is NOT adequate ({ratio}) and no catalogue effect improves "
            f"its predictions{partly}.")
    if strong:
        names = ", ".join(f"{f.variable} (R² {f.r2:.2f})" for f in strong[:3])
        text += (f" The residual size follows {names}: write an effect in those variables "
                 f"(--effect-file).")
    else:
        best = f" (best R² {follow[0].r2:.2f})" if follow else ""
        text += (f" The residual follows no measured variable{best}: check σ (a σ too small, "
                 f"a unit mistake) and the readings.")
    if where:
        text += f" Largest residuals: {where}."
    return text


def _chi2_record(test, s, repeated) -> dict:
    """The χ² test for the diagnosis JSON, with the σ of repeated readings (or None)."""
    lo, hi = test.ratio_interval()
    return {"statistic": test.statistic, "dof": test.dof, "p_value": test.p_value,
            "sigma_source": test.sigma_source, "sigma_hat_mm": test.sigma_hat_mm,
            "sigma_ratio": test.ratio, "sigma_ratio_interval": [lo, hi],
            "tolerance": s.tolerance, "chi2_adequate": test.adequate,
            "misfit_um": test.misfit_um, "practical_um": s.practical_um,
            "repeated": None if repeated is None else repeated.to_dict()}


def diagnose(model, measurements, fit=None, *, settings: DiagnosisSettings | None = None,
             sigma: float | None = None, registry=None, progress=None) -> DiagnosisResult:
    """Diagnose ``model`` on ``measurements``.

    Parameters
    ----------
    model : Model
    measurements : Measurements
        Readings with their σ (m). Readings without σ are tested against the
        σ̂ of the starting model's fit, as on the command line
        (:func:`~doe_calib.estimation.sigma.resolve_sigma`).
    fit : IdentificationResult, optional
        The model's fit to these data; identified here when not given.
    settings : DiagnosisSettings, optional
        Significance level, cross-validation, material gain, adequacy tolerances,
        threads (:class:`~doe_calib.diagnosis.settings.DiagnosisSettings`; default its
        defaults).
    sigma : float, optional
        σ per coordinate, m, for every reading (replacing the readings' own).
    registry : EffectRegistry, optional
        Its :meth:`~doe_calib.model.effects.registry.EffectRegistry.catalogue` is what
        is tested as missing (default the built-in catalogue; user effects:
        ``DEFAULT_REGISTRY.with_file(path)``).
    progress : callable, optional
        ``progress(done, total, note)`` as each chosen candidate is cross-validated:
        candidates done, their number, the effect's spec.

    Returns
    -------
    DiagnosisResult
    """
    s = DiagnosisSettings() if settings is None else settings
    level, min_gain = s.level, s.min_gain
    settled, fit = settled_fit(model, measurements, sigma, fit)
    measurements = settled.measurements
    params = fit.parameters
    res = residuals(model, measurements, params.values)
    rank = int(params.free.sum())
    sigma_mm = float(np.median(measurements.sigma) * 1e3)
    test = adequacy(res, rank, sigma_mm, level, measurements.sigma_source)
    doubt = None if settled.repeated is None or test.sigma_source == REPEATED else \
        settled.repeated.disagreement(sigma_mm)
    copies = copies_words(measurements, model.tool.names)
    outliers = gross_outliers(model, measurements, fit, level, s.tolerance, s.practical_um)
    units = kgf_finding(params, fit.std(), model.robot,
                        measurements.configurations)
    screen, screened = screening_set(measurements)
    split = make_folds(screen, s.folds, s.grouping)
    cv = cross_validated_rms(model, screen, params, split)
    flagged = flagged_poses(res, test.dof / int(res.per_reading.sum()), lines=measurements.line)
    chi2 = _chi2_record(test, s, settled.repeated)
    if outliers:  # no effect is tested on data an outlier pulls
        verdict = outlier_verdict(outliers, _adequacy_words(test))
        return DiagnosisResult(model.spec, res.rms_mm, cv, test.sigma_mm, False, chi2, (), (),
                               tuple(flagged), level, verdict, None, int(res.weighted.size),
                               cv_grouping=split.description, min_gain=min_gain,
                               gross_errors=tuple(dict.fromkeys(o.pose for o in outliers)),
                               notes=tuple(n for n in (units, screened, doubt, copies) if n),
                               outliers=outliers)
    tried = candidate_tests(model, screen, params, registry=registry)
    tests = list(tried.tests)
    chosen = _groups_to_try(tests, level, s.cv_top)
    effects = [parse_effect(t.spec, registry=registry) for t in chosen]
    scored = {t.spec: t for t in score_candidates(model, chosen, effects, params, screen, split,
                                                  s.workers, progress)}
    ranked = sorted(scored.values(), key=lambda t: (_cv_key(t), t.log10_p))
    ranked += [t for t in tests if t.spec not in scored]
    material = _material(ranked, cv, level, min_gain)
    proposed = next((t for t in material if not t.implausible), None)  # the best plausible
    adequate = _is_adequate(test, proposed, s)
    m = len(measurements.configurations)
    size = np.bincount(res.config, (res.weighted ** 2).sum(axis=1), minlength=m)
    count = np.bincount(res.config, minlength=m) * 3
    used = count > 0
    variables = {k: (v[0][used], v[1], v[2]) for k, v in
                 configuration_variables(model.robot, measurements.configurations).items()}
    follow = follows(size[used] / count[used], variables)
    n_poses = len(set(measurements.configurations.pose))
    gross = not adequate and proposed is None and _gross_errors(test, flagged, follow, n_poses)
    verdict = _verdict_words(model, test, adequate, cv, split, ranked, proposed, follow, flagged,
                             gross, s, registry) \
        + _confounded_words(ranked, proposed, level)
    odd = next((t for t in material if t.implausible), None)
    lead = "" if odd is None else sign_lead(model, odd, proposed, cv, split,
                                            describe(odd, model.robot, registry), registry)
    if lead and proposed is None:
        verdict = (f"{lead} Until that is settled the model is NOT adequate "
                   f"({_adequacy_words(test)})." + _confounded_words(ranked, None, level))
    elif lead:
        verdict = f"{lead} Taking the data as they are: {verdict[0].lower()}{verdict[1:]}"
    elif odd is not None and (proposed is None or odd.cv_rms_mm < proposed.cv_rms_mm):
        verdict += (f" Not proposed although it predicts better (cross-validated RMS "
                    f"{odd.cv_rms_mm:.3g} mm): {odd.spec}, {odd.implausible}.")
    spec = None if proposed is None else proposed.spec
    candidates = candidate_records(ranked, model.robot,
                                   [describe(t, model.robot, registry) for t in ranked],
                                   cv, level, min_gain, spec, registry)
    return DiagnosisResult(model.spec, res.rms_mm, cv, test.sigma_mm, adequate, chi2,
                           candidates, tuple(follow), tuple(flagged), level, verdict,
                           spec, int(res.weighted.size),
                           cv_grouping=split.description, min_gain=min_gain,
                           gross_errors=tuple(p["pose"] for p in flagged) if gross else (),
                           notes=tuple(n for n in (units, screened, tried.note(), doubt, copies)
                                       if n))
