"""What a missing effect would add to a fit: its columns, and what the model cannot absorb.

For a model with weighted Jacobian ``J`` (free parameters), a candidate effect
adds columns ``Z``, its parameters' weighted Jacobian at zero effect (the
current model). What the model's own parameters can absorb is removed first:
``Z⊥ = (I − Q Qᵀ) Z`` with ``Q`` an orthonormal basis of ``J``. The
diagnosis tests the residual against ``Z⊥``
(:mod:`doe_calib.diagnosis.effect_tests`); the design asks how large an
effect must be for ``Z⊥`` to reveal it (:mod:`doe_calib.design.discovery`).
"""
from __future__ import annotations

from dataclasses import replace

import numpy as np

from doe_calib.estimation.weighted_residuals import weighted_residual
from doe_calib.model.effects import DEFAULT_REGISTRY, joint_index
from doe_calib.model.marker_model import build_model


def candidate_effects(model, configurations=None, registry=None) -> list:
    """Every catalogue effect instance not yet in ``model`` (one per joint where it applies).

    Effects with several shapes give one candidate per shape;
    ``configurations`` (the measured ones) place data-dependent shapes. The
    catalogue is ``registry``'s (default :data:`~doe_calib.model.effects.DEFAULT_REGISTRY`).
    """
    registry = DEFAULT_REGISTRY if registry is None else registry
    robot = model.robot
    present = {(e.name, None if e.joint is None else joint_index(robot, e.joint))
               for e in model.effects}
    out = []
    for cls in registry.catalogue():
        for e in cls.candidates(robot, configurations):
            j = None if e.joint is None else joint_index(robot, e.joint)
            if (e.name, j) not in present and (e.name, None) not in present:
                out.append(e)
    return out


def augmented(model, params, effect):
    """(model + effect, its parameter set: current values and free flags, new ones free at 0)."""
    big = build_model(model.robot, model.tool, tuple(model.effects) + (effect,))
    return big, grown_parameters(big, params)


def grown_parameters(big, params):
    """The parameter set of ``big`` (a model grown from the one ``params`` fit): the values and
    free flags of ``params``, the new parameters free at nominal."""
    start = big.nominal()
    values = start.values.copy()
    free = start.free.copy()
    reasons = list(start.fixed_reason)
    for i, name in enumerate(params.names):
        k = start.names.index(name)
        values[k], free[k], reasons[k] = params.values[i], params.free[i], params.fixed_reason[i]
    return replace(start, values=values, free=free, fixed_reason=tuple(reasons))


def fitted_basis(model, measurements, params):
    """Weighted residual r (3K,) of the fit and an orthonormal basis Q of its free Jacobian."""
    r, jac = weighted_residual(model, measurements, params.values)
    return r, orthonormal_basis(jac[:, params.free])


def projected_columns(model, measurements, params, effect, q_basis):
    """The candidate's weighted columns Z (3K, q) and Z⊥ = (I − QQᵀ)Z, what the fitted
    model (orthonormal basis ``q_basis`` of its free Jacobian) cannot already absorb."""
    big, bp = augmented(model, params, effect)
    _, z = weighted_residual(big, measurements, bp.values)
    z = z[:, ~np.isin(bp.names, params.names)]
    return z, z - q_basis @ (q_basis.T @ z)


def orthonormal_basis(jac: np.ndarray, tol: float = 1e-9) -> np.ndarray:
    """An orthonormal basis of the columns of ``jac``: its left singular vectors whose
    singular value exceeds ``tol`` times the largest."""
    u, s, _ = np.linalg.svd(jac, full_matrices=False)
    return u[:, s > tol * (s[0] if s.size else 1.0)]
