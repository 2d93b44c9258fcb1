"""After a discovery design's exchange: its poses refined by IPOPT, each keeping its load case
and approach sides, without breaking what the exchange made detectable.

The chosen poses are refined jointly for the D criterion
(:func:`.pose_refinement.refine`, with each pose's own load case and sides);
a refined pose no free path joins to home goes back to its candidate
(:mod:`.reachability`). Then each effect's projected information
``λ_min(N_e)`` (:mod:`.constrained_exchange`) is recomputed at the refined
poses: it must reach ``min(t_e, λ_e at the candidates)`` — a bound met stays
met, a bound missed does not get worse. While it does not, the refined pose
whose return to its candidate lowers the shortfall most goes back.
"""
from __future__ import annotations

from dataclasses import dataclass, replace

import numpy as np

from doe_calib.design.solvers.constrained_exchange import (information_parts,
                                                          projected_information, shortfall)
from doe_calib.design.criteria import log_det
from doe_calib.design.discovery.variants import (effect_columns, observation_rows,
                                                  within_torque_limits)
from doe_calib.design.solvers.pose_refinement import refine as refine_poses
from doe_calib.design.candidates.reachability import revert_unreachable


@dataclass(frozen=True, eq=False)
class RefinedDiscovery:
    """The refined poses of a discovery design.

    Attributes
    ----------
    q : ndarray, shape (n, N)
        The poses kept, rad/m (the candidate's where refinement was not kept).
    blocks : ndarray, shape (n, r, p)
        Their scaled information blocks (model's free parameters).
    outcome : DesignOutcome
        The IPOPT refinement's stage ``refinement``.
    unreachable : int
        Refined poses sent back to their candidate: no free path from home.
    detection : int
        Refined poses sent back to their candidate: they would break a detection bound.
    """

    q: np.ndarray
    blocks: np.ndarray
    outcome: object
    unreachable: int
    detection: int

    def to_dict(self) -> dict:
        return {**self.outcome.to_dict(), "reverted_unreachable": self.unreachable,
                "reverted_for_detection": self.detection}


def chosen_variants(cand, chosen, q=None):
    """The chosen candidates as variants of their own poses (``q``: other angles for them)."""
    chosen = np.asarray(chosen)
    return replace(cand, q=cand.q[cand.pose[chosen]] if q is None else np.asarray(q),
                   pose=np.arange(len(chosen)), case=cand.case[chosen],
                   approach=cand.approach[chosen])


def _columns(model, params, sub, effects, sigma):
    raw = observation_rows(model, params.values, sub) / sigma
    b = raw[..., params.free] * params.scales[params.free]
    return b, [effect_columns(model, params, e, sub, sigma)[0] for e in effects]


def _lambda(b, zs):
    """λ_min of each effect's projected information at the poses of ``b`` (n, r, p)."""
    return projected_information(*information_parts(b, zs))


def refine_discovery(model, params, cand, chosen, sigma: float, feasibility, effects, targets,
                     collision=None, home=None, constraints=None) -> RefinedDiscovery:
    """Refine the chosen variants' poses, keeping the detection bounds the exchange met.

    Parameters
    ----------
    model : Model
    params : ParameterSet
        The design's parameters (free: those designed for).
    cand : Variants
    chosen : ndarray of int, shape (n,)
    sigma : float
        Tracker σ per coordinate, m.
    feasibility : Feasibility
    effects : sequence of Effect
        The effects whose detection bounds are kept.
    targets : array_like, shape (E,)
        Their ``λ*(P)/S²`` (:func:`.variants.detection_target`).
    collision : CollisionModel, optional
    home : ndarray, shape (N,), optional
        With ``collision``: refined poses must stay joined to it.
    constraints : DesignConstraints, optional
        Its joint bounds (for the equivalent angles, :func:`.reachability.unreachable`)
        and load-torque limits: a refined pose whose own load case exceeds them goes
        back to its candidate (default ``feasibility.constraints``).

    Returns
    -------
    RefinedDiscovery
    """
    sub0 = chosen_variants(cand, chosen)
    q0 = sub0.q
    outcome = refine_poses(model, params, (), sigma, q0, feasibility, "D", collision=collision,
                           variants=[([cand.cases[c] for c in cand.load_cases(k)], cand.approach[k])
                                     for k in chosen])
    b0, z0 = _columns(model, params, sub0, effects, sigma)
    if not outcome.accepted:
        return RefinedDiscovery(q0, b0, outcome, 0, 0)
    constraints = feasibility.constraints if constraints is None else constraints
    q1, far = outcome.q, 0
    heavy = ~within_torque_limits(model, params.values, constraints,
                                  chosen_variants(cand, chosen, q1))
    q1 = np.where(heavy[:, None], q0, q1)
    if home is not None:
        q1, far = revert_unreachable(collision, q1, q0, home, model.robot, constraints)
    b1, z1 = _columns(model, params, chosen_variants(cand, chosen, q1), effects, sigma)
    need = np.minimum(np.asarray(targets, float), _lambda(b0, z0))

    def mixed(refined):
        pick = refined[:, None, None]
        return (np.where(pick, b1, b0), [np.where(pick, a, b) for a, b in zip(z1, z0)])

    def short(refined):
        return float(shortfall(_lambda(*mixed(refined)), need))

    refined, reverted = np.ones(len(q0), bool), 0
    while refined.any() and short(refined) > 1e-9:
        tries = {int(i): short(np.where(np.arange(len(q0)) == i, False, refined))
                 for i in np.flatnonzero(refined)}
        refined[min(tries, key=tries.get)] = False
        reverted += 1
    b = mixed(refined)[0]
    if log_det(np.einsum("kri,krj->ij", b, b)) <= log_det(np.einsum("kri,krj->ij", b0, b0)):
        return RefinedDiscovery(q0, b0, outcome, far, len(q0))
    return RefinedDiscovery(np.where(refined[:, None], q1, q0), b, outcome, far, reverted)
