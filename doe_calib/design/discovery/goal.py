"""Designs that can discover: D-optimal poses, load cases and approach sides subject to every
listed effect being detectable at a given size.

``doe-calib design --criterion D --detect EFFECTS --min-power P --detect-size S``.
Each candidate is a pose in one variant (:mod:`.variants`):
measured unloaded and under one allowed load case (``--load`` ×
``--load-directions``, :mod:`.load_directions`), with the approach side of
every joint whose approach backlash is listed. Effect e is detectable at
size S with power P (χ² score test at level α, the model's own parameters
estimated too, :mod:`.detection`) when the smallest eigenvalue of its
projected information ``N_e = Z⊥ᵀZ⊥`` reaches ``λ*(P)/S²``. The method is a
constrained exchange (:mod:`.constrained_exchange`), started from the
unconstrained D-optimal choice among the same variants: first lower the
shortfall of the bounds, then raise log det M among the designs that meet
them. An effect that no candidate (all of them together) reveals is left out
of the bounds and said so; one that the n poses cannot reveal at S gets the
best size reached. Each effect's ``min_detectable`` is then recomputed on the
design (:func:`.detection.with_detectability`).
"""
from __future__ import annotations

from dataclasses import dataclass, replace
from typing import ClassVar

import numpy as np

from doe_calib.design.candidates.clearances import pose_clearances
from doe_calib.design.criteria import AOptimal, DOptimal, EOptimal, log_det
from doe_calib.design.detectability import INVISIBLE
from doe_calib.design.discovery.detection import detect_effects, with_detectability
from doe_calib.design.discovery.load_directions import directed_loads
from doe_calib.design.discovery.refinement import chosen_variants, refine_discovery
from doe_calib.design.discovery.variants import (approach_joints, detection_target,
                                                 effect_columns, free_parameters,
                                                 observation_rows, variants,
                                                 within_torque_limits)
from doe_calib.design.pipeline import Goal, constraints_used
from doe_calib.design.predicted_std import design_std
from doe_calib.design.result import CandidateCount, DesignResult
from doe_calib.design.solvers.constrained_exchange import (constrained_exchange,
                                                          projected_information)
from doe_calib.design.solvers.exchange import exact_design
from doe_calib.design.solvers.relaxation import information, relax
from doe_calib.errors import OptionError, SolverError
from doe_calib.io.measurements import Configurations

#: Candidates searched by the exchange: the relaxation's best, and each effect's richest.
POOL, POOL_PER_EFFECT = 1500, 300


@dataclass(frozen=True)
class DiscoveryGoal(Goal):
    """What a discovery design must be able to reveal.

    Attributes
    ----------
    effects : str
        ``+``-joined effect strings (or ``catalogue``), as ``--detect``.
    size : float or None
        ``--detect-size``: the size each effect must be detected at, its display unit
        (deg, mm, …; SI when its parameters' units differ). None: no detection bound, the
        D-optimal choice of poses, load cases and approach sides (``--load-directions``
        with plain ``--detect``); the detectability is reported.
    power, alpha : float
        Power asked (``--min-power``) of the χ² score test at level ``alpha``.
    directions : tuple of tuple
        Allowed unit force directions of the load cases
        (:func:`.load_directions.parse_directions`).
    registry : EffectRegistry, optional
    """

    effects: str
    size: float | None
    power: float = 0.8
    alpha: float = 0.05
    directions: tuple = ((0.0, 0.0, -1.0),)
    registry: object = None

    def __post_init__(self):
        if self.size is not None and not self.size > 0:
            raise OptionError(f"--detect-size {self.size:g}: give a positive size (the effect's "
                              f"display unit, e.g. deg)")
        if not 0 < self.alpha < self.power < 1:
            raise OptionError(f"--alpha {self.alpha:g} and --min-power {self.power:g}: give "
                              f"0 < alpha < power < 1")

    #: Each candidate is judged with its own load case
    #: (:func:`.variants.within_torque_limits`).
    own_load_case: ClassVar[bool] = True

    def information(self, setting, candidates, stage) -> DiscoveryInformation:
        """The variants of the candidate poses (load case × approach sides), their blocks,
        each effect's columns and detection target, and which effects they can reveal."""
        model, params, n_poses = setting.model, setting.params, setting.n_poses
        q = candidates.poses.q
        if len(q) < n_poses:
            raise SolverError(f"only {len(q)} feasible candidates for {n_poses} poses")
        effects = detect_effects(model, self.effects, Configurations.from_arrays(q),
                                 self.registry)
        cases = directed_loads(setting.loads, self.directions)
        cand = variants(q, cases, approach_joints(model, effects), model.robot.n_joints)
        within = within_torque_limits(model, params.values, setting.constraints, cand)
        drawn = candidates.poses.count()
        if not within.all():
            cand = cand.subset(within)
            drawn = replace(drawn, removed={
                **drawn.removed,
                "load torque (the variant's own load case)": int((~within).sum())})
        stage("information", f"{len(cand)} candidates ({len(q)} poses × {max(len(cases), 1)} "
                             f"load case(s) × {2 ** len(cand.approach_joints)} approach "
                             f"side(s))")
        raw = observation_rows(model, params.values, cand) / setting.sigma
        params = free_parameters(params, raw, cand)
        blocks = raw[..., params.free] * params.scales[params.free]
        columns = [effect_columns(model, params, e, cand, setting.sigma) for e in effects]
        zblocks = [z for z, _ in columns]
        targets = np.array([] if self.size is None else
                           [detection_target(e, model, own, self.size, self.alpha, self.power)
                            for e, (_, own) in zip(effects, columns)])
        # what every candidate together reveals: an effect they cannot is left out of the bounds
        m_all = information(blocks, np.ones(len(cand)))
        everything = projected_information(
            m_all, [np.einsum("kri,krj->ij", blocks, z) for z in zblocks],
            [np.einsum("kri,krj->ij", z, z) for z in zblocks])
        reach = [np.sqrt(max(lam, 0.0)) * min(p_.scale for p_ in e.parameters(model.robot))
                 >= INVISIBLE for lam, e in zip(everything, effects)]
        keep = [i for i, ok in enumerate(reach) if ok and self.size is not None]
        return DiscoveryInformation(params, effects, cases, cand, blocks, zblocks, targets,
                                    tuple(reach), tuple(keep), drawn, q, cand.pose)

    def relaxation(self, setting, info, stage):
        stage("relaxation", f"D criterion over {len(info.cand)} candidates")
        return relax(info.blocks, DOptimal())

    def exchange(self, setting, info, relaxed, allowed, stage) -> Found:
        """The unconstrained D-optimal choice of distinct poses among the ``allowed``, then
        the constrained exchange that meets the detection bounds from it."""
        n_poses, blocks, cand = setting.n_poses, info.blocks, info.cand
        ok = allowed[cand.pose]
        sub = np.flatnonzero(ok)
        start = sub[exact_design(blocks[sub], n_poses, "D", relaxed.weights[sub]).indices]
        pool = _pool(relaxed, info.zblocks)
        pool = pool[ok[pool]]
        stage("exchange", f"{n_poses} poses, distinct")
        free = constrained_exchange(blocks, [], [], _dedupe(start, blocks, cand.pose, ok),
                                    cand.pose, pool)
        found = free
        if info.keep:
            stage("exchange", f"discovery: {len(info.keep)} detection bound(s)")
            found = constrained_exchange(blocks, [info.zblocks[i] for i in info.keep],
                                         info.targets[list(info.keep)], free.indices,
                                         cand.pose, pool)
        return Found(free, found)

    def refinement(self, setting, candidates, info, choice, stage):
        """IPOPT on the chosen poses, each keeping its load case and approach sides, no
        detection bound lost (:func:`.refinement.refine_discovery`)."""
        stage("refinement", f"IPOPT on {setting.n_poses} poses, each keeping its load case")
        keep = list(info.keep)
        return refine_discovery(setting.model, info.params, _reached(info, choice),
                                choice.chosen, setting.sigma, candidates.feasibility,
                                [info.effects[i] for i in keep], info.targets[keep],
                                setting.collision,
                                None if choice.reachability is None
                                else choice.reachability.home, setting.constraints)

    def bound(self, setting, info, relaxed, refined, stage):
        if refined is None or not refined.outcome.accepted:
            return relaxed
        stage("bound", "relaxation with the refined poses as candidates")
        return relax(np.concatenate([info.blocks, refined.blocks]), DOptimal(),
                     start=np.r_[relaxed.weights, np.zeros(setting.n_poses)])

    def assessment(self, setting, candidates, info, relaxed, choice, refined, bound,
                   stage) -> DesignResult:
        model, n_poses, params = setting.model, setting.n_poses, info.params
        free, found, chosen = choice.made.free, choice.made.found, choice.chosen
        design_blocks = info.blocks[chosen] if refined is None else refined.blocks
        m = information(design_blocks, np.ones(n_poses))
        value = log_det(m)
        if not np.isfinite(value):
            raise SolverError(f"the {n_poses} poses chosen cannot identify every parameter of "
                              f"the model; ask for more poses")
        stages = {"relaxation": relaxed.to_dict(), "exchange": free.to_dict()}
        if refined is not None:
            stages["refinement"] = refined.to_dict()
        limit = bound.bound(n_poses)
        p = info.blocks.shape[2]
        d_eff = DOptimal().efficiency(value, limit, p)
        # against the unconstrained exchange, both before any refinement
        versus = float(np.exp(((value if refined is None else found.value) - free.value) / p))
        cand = _reached(info, choice)
        final = chosen_variants(cand, chosen, None if refined is None else refined.q)
        cfg = final.configurations(model, params.values, None,
                                   [str(i + 1) for i in range(n_poses)])
        reach, clearances = choice.reachability, ()
        if reach is not None:
            reach = replace(reach, reverted=0 if refined is None else refined.unreachable)
            clearances = pose_clearances(setting.collision, final.q)
        result = DesignResult(
            robot=model.robot, tool=model.tool, model=model.spec, configurations=cfg,
            criterion="D", value=value, bound=limit, efficiency=d_eff,
            predicted_std=design_std(params, m),
            constraints=constraints_used(setting, info.cases, reach),
            efficiencies={"D": d_eff},
            criteria={c.name: c.value(m) for c in (DOptimal(), AOptimal(), EOptimal())},
            candidates=replace(info.candidates, variants=len(cand)),
            sigma_mm=1000.0 * setting.sigma, clearances=clearances, outcomes=stages)
        result = with_detectability(result, model, self.effects, self.alpha, self.power,
                                    self.registry)
        return _with_outcome(result, self, info.reach, cand, free, found, versus)


@dataclass(frozen=True, eq=False)
class DiscoveryInformation:
    """The information stage of a discovery design: the parameters (those no variant
    identifies fixed), the effects to reveal, every load case a pose may take, the
    candidates ``cand`` (each pose in each load case and approach sides, within the load
    torques), their ``blocks`` (K, r, p) and each effect's columns ``zblocks`` (K, r, q_e),
    each effect's bound on λ_min of its projected information (``targets``, empty without a
    size), whether all candidates together reveal it (``reach``), the effects bounded
    (``keep``), the candidates drawn and removed, the candidate poses ``q`` (P, N), rad (m),
    and the pose of each candidate."""

    params: object
    effects: list
    cases: tuple
    cand: object
    blocks: np.ndarray
    zblocks: list
    targets: np.ndarray
    reach: tuple
    keep: tuple
    candidates: CandidateCount
    q: np.ndarray
    pose_of: np.ndarray


@dataclass(frozen=True, eq=False)
class Found:
    """The exchange stage of a discovery design: the unconstrained choice and the one that
    meets the detection bounds (the same without bounds)."""

    free: object
    found: object

    @property
    def indices(self) -> np.ndarray:
        return self.found.indices


def _reached(info, choice):
    """The variants with each checked pose at the angles it is reached at."""
    return info.cand if choice.reachability is None else replace(info.cand, q=choice.q)


def _dedupe(start, blocks, pose_of, allowed):
    """The start with repeated poses replaced by the best D candidate of an unused pose
    (among the ``allowed`` candidates)."""
    chosen = []
    for k in start:
        if pose_of[k] in {pose_of[j] for j in chosen}:
            m = information(blocks[chosen], np.ones(len(chosen))) if chosen else 0.0
            free = np.flatnonzero(~np.isin(pose_of, [pose_of[j] for j in chosen]) & allowed)
            gain = [log_det(m + blocks[j].T @ blocks[j] + 1e-9 * np.eye(blocks.shape[2]))
                    for j in free[:2000]]
            k = int(free[int(np.argmax(gain))])
        chosen.append(int(k))
    return chosen


def _pool(relaxed, zblocks):
    order = list(np.argsort(-relaxed.weights)[:POOL])
    for z in zblocks:
        order += list(np.argsort(-(z ** 2).sum(axis=(1, 2)))[:POOL_PER_EFFECT])
    return np.unique(order)


def _with_outcome(result, goal, reach, cand, free, found, versus):
    """``result`` with the discovery stage (``load_choice`` without a size)."""
    chose = {"load_directions": [list(d) for d in goal.directions],
             "approach_joints": [result.robot.joints[j].name for j in cand.approach_joints]}
    used = _cases_used(cand, found.indices)
    if goal.size is None:
        stage = {"method": "exchange over poses × load cases × approach sides",
                 "status": found.status, **chose, "load_cases_used": used}
        return replace(result, outcomes={**result.outcomes, "load_choice": stage})
    rows = [{"effect": det.effect, "unit": det.unit, "asked": goal.size,
             "min_detectable": det.min_detectable if np.isfinite(det.min_detectable) else None,
             "met": bool(det.detectable and det.min_detectable <= goal.size * (1 + 1e-6)),
             "revealable": bool(ok)} for det, ok in zip(result.detectability, reach)]
    stage = {"method": "constrained exchange", "status": found.status, "size": goal.size,
             "power": goal.power, "alpha": goal.alpha, **chose,
             "unconstrained_log_det": free.value, "d_efficiency_vs_unconstrained": versus,
             "load_cases_used": used, "effects": rows}
    return replace(result, outcomes={**result.outcomes, "discovery": stage})


def _cases_used(cand, chosen) -> dict:
    """Load case (its spec) → how many chosen poses are measured under it."""
    used = {}
    for k in chosen:
        c = int(cand.case[k])
        name = "unloaded only" if c < 0 else cand.cases[c].spec()
        used[name] = used.get(name, 0) + 1
    return used
