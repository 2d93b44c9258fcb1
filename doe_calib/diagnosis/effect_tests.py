"""Which missing effect explains the residual: score (F) tests on projected columns.

For a fitted model with weighted residual ``r`` and weighted Jacobian ``J``
(free parameters), a candidate effect adds columns ``Z`` (its parameters'
Jacobian at zero, i.e. at the current model). What the current parameters
can already absorb is removed first: ``Z⊥ = (I − Q Qᵀ) Z`` with ``Q`` an
orthonormal basis of ``J``. The part of ``r`` in the span of ``Z⊥``,
``ΔSS = ‖U⊥ᵀ r‖²``, is what adding the effect would remove to first order
(the Lagrange-multiplier/score statistic), and

``F = (ΔSS / q) / ((‖r‖² − ΔSS) / (3K − rank J − q))  ~  F(q, 3K − rank J − q)``

under "the effect is absent", with ``q`` the rank of ``Z⊥`` and 3K the coordinates: less 3
per socket's point, ballbar pivot and plane, which the residual and the columns have
eliminated, and 2 per plane touch or ballbar length, one coordinate each. The F form
does not depend on σ being right. p-values are Bonferroni-adjusted over
all candidates tried, so a correct model is rarely sent looking; candidates
are ordered by ``log10 p`` (which does not underflow).
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from scipy.special import fdtrc

from doe_calib.diagnosis.candidate import Candidate
from doe_calib.diagnosis.candidate_batch import batched_columns
from doe_calib.diagnosis.held_out_contacts import eliminated_coordinates
from doe_calib.design.detectability import MOSTLY_ABSORBED, absorbing_parameters, assess
from doe_calib.errors import DoeCalibError
from doe_calib.estimation.effect_signature import (candidate_effects, fitted_basis,
                                                   projected_columns)
from doe_calib.estimation.weighted_residuals import weighted_residual
from doe_calib.model.effects import joint_index
from doe_calib.model.marker_model import describe_model


def _failure(exc) -> str:
    return str(exc) or type(exc).__name__


def failure_note(failed, what: str) -> str:
    """``failed`` (``(spec, reason)`` pairs) in words: "2 {what}s could not be computed:
    spec: reason, …" ("" when none failed)."""
    if not failed:
        return ""
    n = len(failed)
    return (f"{n} {what}{'s' if n > 1 else ''} could not be computed: "
            + ", ".join(f"{s}: {why}" for s, why in failed))


def candidate_columns(model, measurements, params, effects, q_basis) -> tuple:
    """Every candidate's columns ``(effect, Z, Z⊥)`` (:func:`projected_columns`), and
    ``(spec, reason)`` of those that could not be built.

    The columns come from one batch of the candidates
    (:func:`~doe_calib.diagnosis.candidate_batch.batched_columns`); a candidate that does
    not fit in it is built alone.
    """
    ok, failed = [], []
    names = set(model.description.nominal().names)
    for e in effects:  # what building model + e alone would refuse (clashing parameters)
        try:
            own = [p.name for p in e.parameters(model.robot)]
            if names.intersection(own) or len(set(own)) < len(own):
                describe_model(model.robot, model.tool, tuple(model.effects) + (e,))  # says it
            ok.append(e)
        except (DoeCalibError, ValueError) as exc:
            failed.append((e.spec(), _failure(exc)))
    out = []
    for e, z in zip(ok, batched_columns(model, measurements, params.values, ok)):
        try:
            out.append((e, z, z - q_basis @ (q_basis.T @ z)) if z is not None else
                       (e, *projected_columns(model, measurements, params, e, q_basis)))
        except (DoeCalibError, ValueError, np.linalg.LinAlgError) as exc:
            failed.append((e.spec(), _failure(exc)))
    return out, failed


#: A candidate this significant before the Bonferroni correction, and mostly absorbed by
#: the model's own parameters, is named with the parameters that absorb it.
SIGNIFICANT_RAW = 1e-3


@dataclass(frozen=True)
class CandidateTests:
    """The candidates' tests and the candidates whose test could not be computed.

    Attributes
    ----------
    tests : tuple of Candidate
        Each candidate's test (a :class:`~doe_calib.diagnosis.candidate.Candidate` without
        the decision), strongest evidence (smallest p, as log10) first; p-values Bonferroni-adjusted
        over every candidate tried, those in ``failed`` included.
    failed : tuple of (str, str)
        ``(spec, reason)`` of each candidate whose model or columns could not be built.
    """

    tests: tuple
    failed: tuple = ()

    def note(self) -> str:
        """The failed candidates in words (empty when none failed)."""
        note = failure_note(self.failed, "candidate")
        return note and note + (f" ({'they count' if len(self.failed) > 1 else 'it counts'} "
                                "in the Bonferroni correction)")


def candidate_tests(model, measurements, params, effects=None,
                    registry=None) -> CandidateTests:
    """Score/F test of every candidate effect against the residual of ``params``.

    Parameters
    ----------
    model : Model
        The fitted model.
    measurements : Measurements
    params : ParameterSet
        The fitted values and free flags.
    effects : list of Effect, optional
        Candidates; default :func:`candidate_effects` of ``registry``.
    registry : EffectRegistry, optional
        Whose catalogue the default candidates come from (default the built-in one).

    Returns
    -------
    CandidateTests
        A candidate whose columns cannot be built is named in ``failed`` and
        still counts in the Bonferroni correction (it was tried).
    """
    if effects is None:
        effects = candidate_effects(model, measurements.configurations, registry)
    r, q_basis = fitted_basis(model, measurements, params)
    rank_j = q_basis.shape[1] + eliminated_coordinates(measurements)  # sockets, planes, …
    ss = float(r @ r)
    jac = []  # the free weighted Jacobian, made once and only when words need it

    def jacobian():
        if not jac:
            jac.append(weighted_residual(model, measurements, params.values)[1][:, params.free])
        return jac[0]

    columns, failed = candidate_columns(model, measurements, params, effects, q_basis)
    n = max(len(columns) + len(failed), 1)  # Bonferroni over every candidate tried
    out = []
    for e, z, zp in columns:
        norm2 = float((z ** 2).sum())
        absorbed = 1.0 - float((zp ** 2).sum()) / norm2 if norm2 > 0 else 1.0
        svd = np.linalg.svd(zp, full_matrices=False)
        detection = assess(e.spec(), e.parameters(model.robot), params, z, zp, jacobian,
                           zp_svd=svd)
        scale = np.sqrt(max(norm2, 1e-300) / max(z.shape[1], 1))
        u, s, _ = svd
        keep = s > 1e-6 * scale
        q = int(keep.sum())
        dof = len(r) - rank_j - q
        f, log_p, frac, by = 0.0, 0.0, 0.0, ()
        if q == 0 or dof <= 0:
            q, dof = 0, None
        else:
            dss = float(((u[:, keep].T @ r) ** 2).sum())
            f = (dss / q) / max((ss - dss) / dof, 1e-300)
            with np.errstate(divide="ignore"):  # −inf (p = 0) past underflow, no warning
                log_p = float(np.log(fdtrc(q, dof, f)))
            frac = dss / ss if ss > 0 else 0.0
            if absorbed > MOSTLY_ABSORBED and log_p < np.log(SIGNIFICANT_RAW):
                # what the model's own parameters made of the signature the residual asks for
                theta = np.linalg.lstsq(z, r, rcond=None)[0]
                by = tuple(absorbing_parameters(params, jacobian(), z @ theta))
        out.append(Candidate(
            e.name, e.spec(), None if e.joint is None else joint_index(model.robot, e.joint) + 1,
            z.shape[1], q, dof, float(f), float(min(1.0, np.exp(log_p) * n)),
            float(np.exp(log_p)), log_p / np.log(10), frac, absorbed, detection, by))
    return CandidateTests(tuple(sorted(out, key=lambda c: (c.log10_p, -c.statistic))),
                          tuple(failed))


def test_candidates(model, measurements, params, effects=None,
                    registry=None) -> list[Candidate]:
    """The tests of :func:`candidate_tests` (those computed), strongest evidence first."""
    return list(candidate_tests(model, measurements, params, effects, registry).tests)
