"""The chosen candidates scored: each grown model built, fitted, then cross-validated.

The candidates are independent and CasADi evaluates without Python's lock:
``workers`` threads fit them at once, each in its own evaluation workspace
(:func:`~doe_calib.model.evaluation.thread_workspace`), while the calling
thread builds the next grown model (CasADi's symbolic construction is not
thread-safe). The scores are those of fitting one after another, bit for bit.
The toolkit's warnings of these fits are held back once for every thread (a
``warnings.catch_warnings`` per thread would race on the global filters).
"""
from __future__ import annotations

import os
import warnings
from concurrent.futures import ThreadPoolExecutor
from dataclasses import replace

from doe_calib.diagnosis.candidate import FittedSize
from doe_calib.diagnosis.cross_validation import cross_validated_rms
from doe_calib.errors import DoeCalibError, DoeCalibWarning
from doe_calib.estimation.effect_signature import grown_parameters
from doe_calib.estimation.identify import FitSettings, identify
from doe_calib.estimation.plausibility import beyond_plausible, out_of_bounds, value_words
from doe_calib.model.marker_model import build_model

#: Threads at most by default: beyond, the fits' Python parts wait on each other.
MAX_WORKERS = 4
#: A grown model's fit, started from the fit it grew from (its frame already registered),
#: fitted whole to compare with the others.
GROWN = FitSettings(select="none", register=False)


def score_candidates(model, candidates, effects, params, measurements, folds,
                     workers: int | None = None, progress=None) -> list:
    """Build, fit and cross-validate each model grown from ``model`` by one of ``effects``.

    The grown models start from ``params`` (``model``'s fit) and are fitted and
    cross-validated over ``folds`` on ``measurements``; ``workers`` threads fit at once
    (default: the machine's cores, at most :data:`MAX_WORKERS`; 1: one after another).
    ``progress(done, total, spec)`` is told as each is scored, in order.

    Returns
    -------
    list of Candidate
        ``candidates`` (the tests of ``effects``, in their order) with the grown model's
        cross-validated RMS (mm; NaN where its fit failed), its effect's fitted sizes and
        what is physically implausible about them (:func:`fitted_sizes`).
    """
    workers = min(MAX_WORKERS, os.cpu_count() or 1) if workers is None else max(1, int(workers))
    def grown(effect):
        return build_model(model.robot, model.tool, tuple(model.effects) + (effect,))

    with warnings.catch_warnings(), ThreadPoolExecutor(max(1, min(workers, len(effects)))) as pool:
        warnings.simplefilter("ignore", DoeCalibWarning)
        if workers == 1 or len(effects) < 2:  # in this thread, as the caller's own fits
            scores = (_score(grown(e), e, c, params, measurements, folds)
                      for c, e in zip(candidates, effects))
        else:  # each built while the workers fit
            scores = (f.result() for f in [pool.submit(_score, grown(e), e, c, params,
                                                       measurements, folds)
                                           for c, e in zip(candidates, effects)])
        out = []
        for i, effect in enumerate(effects):
            if progress:
                progress(i, len(effects), effect.spec())
            out.append(next(scores))
        return out


def _score(big, effect, candidate, params, measurements, folds):
    bp = grown_parameters(big, params)
    try:  # folds start from the grown model's own fit: what they hold fixed is then right
        fit = identify(big, measurements, bp, settings=GROWN)
    except DoeCalibError:
        return replace(candidate, cv_rms_mm=float("nan"))
    new = [n for n in fit.parameters.names if n not in params.names]
    sizes, odd = fitted_sizes(fit, new, effect)
    return replace(candidate, cv_rms_mm=cross_validated_rms(big, measurements, fit.parameters,
                                                            folds), sizes=sizes, implausible=odd)


def fitted_sizes(fit, names, effect) -> tuple:
    """The new parameters' values ± a-posteriori std in display units (:class:`FittedSize`),
    and a note on those beyond their bounds or plausible range (the parameters' and
    ``effect``'s words)."""
    ps = fit.parameters
    std = fit.std()
    sizes = []
    for name in names:
        i = ps.names.index(name)
        p = ps.parameters[i]
        f = p.display_factor
        sizes.append(FittedSize(name, float(ps.values[i] * f),
                                float(std[i] * f) if ps.free[i] else None, p.display_unit,
                                bool(ps.free[i])))
    odd = []
    wrong = out_of_bounds(ps, std, names)
    if wrong:
        words = [value_words(p, ps[p.name], s) for p, _, s in wrong]
        low = all(v < p.bounds[0] for p, v, _ in wrong)
        odd.append(("negative " if low and all(p.bounds[0] == 0 for p, *_ in wrong) else
                    "beyond physical bounds ") + ", ".join(words))
        signs = list(dict.fromkeys(p.sign for p, *_ in wrong if p.sign))
        odd[-1] += "".join(f" ({text})" for text in signs)
    far = beyond_plausible(ps, names)
    if far:
        words = [value_words(p, v, std[ps.names.index(p.name)]) for p, v in far]
        odd.append(f"{', '.join(words)}: {effect.implausible_words}")
    note = ("physically implausible: " + "; ".join(odd)) if odd else ""
    return tuple(sizes), note
