"""The design pipeline: feasible candidates → relaxation (bound) → exact exchange →
continuous refinement → bound recomputed with the refined poses → result.
"""
from __future__ import annotations

import logging
import time
from dataclasses import replace

import numpy as np

from doe_calib.design.candidate_file import CandidatePoses, screened_candidates
from doe_calib.design.candidate_poses import feasible_candidates
from doe_calib.design.clearances import collision_note, pose_clearances
from doe_calib.design.constraints import DesignConstraints
from doe_calib.design.criteria import (
    AOptimal,
    Criterion,
    DOptimal,
    EOptimal,
    TaskOptimal,
    check,
    log_det,
)
from doe_calib.design.exchange import exact_design
from doe_calib.design.feasibility import build_feasibility
from doe_calib.design.pose_refinement import refine as refine_poses
from doe_calib.design.reachability import (
    free_home,
    home_pose,
    reachability_note,
    unreachable,
)
from doe_calib.design.problem import (
    blocks_for,
    check_enough_poses,
    design_parameters,
    load_configurations,
    task_matrix,
)
from doe_calib.design.relaxation import (
    equivalence_ratio,
    information,
    packed_information,
    packed_size,
    relax,
)
from doe_calib.design.result import DesignResult
from doe_calib.errors import OptionError, SolverError
from doe_calib.io.setting_ranges import positive, whole

log = logging.getLogger(__name__)

_RANDOM_DESIGNS = 100
#: Rounds of exchange with unreachable chosen poses removed from the candidates.
_REACH_ROUNDS = 8

class _Stages:
    """Reports each stage to ``progress(stage, note)`` and logs its duration."""

    def __init__(self, progress):
        self.progress, self.name, self.start = progress, None, time.perf_counter()

    def __call__(self, name: str, note: str = "") -> None:
        now = time.perf_counter()
        if self.name is not None and name != self.name:
            log.info("design stage %s: %.2f s", self.name, now - self.start)
        if name != self.name:
            self.name, self.start = name, now
        if self.progress is not None:
            self.progress(name, note)

    def iterations(self, name):
        return lambda it, gap: self(name, f"iteration {it}, gap {gap:.3g}")


def optimal_design(model, n_poses: int, loads=(), candidates: int | CandidatePoses = 20000,
                   sigma: float = 2e-5, criterion="D", task=None, task_point=(0.0, 0.0, 0.0),
                   constraints: DesignConstraints | None = None, refine: bool = True,
                   params=None, rng=None, progress=None, collision=None,
                   home=None, discovery=None) -> DesignResult:
    """Optimal N-pose design for ``model`` under constraints.

    Parameters
    ----------
    model : Model
    n_poses : int
        Poses to measure; each is measured unloaded and under every load case.
        At least what the identifiable parameters need
        (:func:`.problem.check_enough_poses`).
    loads : sequence of LoadCase
    candidates : int or CandidatePoses
        Feasible candidate poses, drawn uniformly inside the joint bounds; or
        named poses (:func:`.candidate_file.read_candidates`: taught, known-safe
        or measured ones) screened by the same constraints, designed over as
        they are (no continuous refinement), the chosen ones keeping their names.
    sigma : float
        Tracker σ per coordinate, m.
    criterion : {"D", "A", "E", "task"} or Criterion
        A name or a criterion object (:func:`.criteria.criterion`); the task
        criterion is asked for by name with ``task``, since its matrix
        depends on the parameters designed for.
    task : Configurations, optional
        Task poses and their loads (wrenches), for the task criterion.
    task_point : array_like, shape (3,)
        The task point in the flange frame, m (default the flange origin).
    constraints : DesignConstraints, optional
        Default: the URDF joint limits with a 1 deg (mm) margin.
    refine : bool
        Run the continuous IPOPT refinement.
    params : ParameterSet, optional
        Expected values (default nominal); parameters no candidate can
        identify are fixed.
    progress : callable(stage, note), optional
    collision : CollisionModel, optional
        Candidates closer than its clearances are rejected, refined poses
        that lose it step back, and each pose's clearance is reported
        (:func:`doe_calib.collision.build_collision_model`; None: no check).
        Then, too, only poses joined to ``home`` by a free path at its move
        clearance and whose tracker beams are free are kept
        (:mod:`.reachability`): an unreachable chosen pose is removed from the
        candidates and the exchange run again, an unreachable refined pose
        goes back to its candidate.
    home : array_like, shape (N,), optional
        The pose programs start from, rad (m); default the URDF zero clipped
        inside the joint bounds (:func:`.reachability.home_pose`), or the
        free candidate nearest it when it is not free
        (:func:`.reachability.free_home`); recorded in the result's
        ``constraints["reachability"]["home"]`` (deg, mm).
    """
    if isinstance(criterion, TaskOptimal):
        raise OptionError("ask for the task criterion by name, criterion=\"task\", with task= "
                          "poses: its matrix depends on the parameters designed for")
    check(criterion, task)
    whole("n_poses", n_poses, 1, "pose")
    positive("sigma", sigma, "m")
    if not isinstance(candidates, CandidatePoses):
        whole("candidates", candidates, 1)
    rng = np.random.default_rng() if rng is None else rng
    params = model.nominal() if params is None else params
    constraints = DesignConstraints.from_robot(model.robot) if constraints is None else constraints
    stage = _Stages(progress)
    # a discovery design judges each pose's load torques with its own load case
    feasibility = build_feasibility(model, params.values, constraints if discovery is None
                                    else replace(constraints, torque_limits=None), loads)
    if isinstance(candidates, CandidatePoses):
        stage("candidates", f"screening the {len(candidates)} poses of {candidates.source}")
        cands, refine = screened_candidates(feasibility, model.robot, candidates, collision), False
    else:
        stage("candidates", f"drawing {candidates} feasible poses")
        cands = feasible_candidates(feasibility, model.robot, candidates, rng, collision)
    if len(cands.q) < n_poses:
        raise SolverError(f"only {len(cands.q)} feasible candidates for {n_poses} poses")
    if discovery is not None:
        if criterion != "D":
            raise OptionError(f"--detect-size and --load-directions designs maximise the D "
                              f"criterion; got "
                              f"--criterion {criterion}")
        from doe_calib.design.discovery import discovery_design  # its statistics load slowly

        return discovery_design(model, params, cands.q, loads, n_poses, sigma, discovery,
                                constraints, cands.to_dict(), progress=stage, refine=refine,
                                feasibility=feasibility, collision=collision, home=home)
    params = design_parameters(model, params, cands.q, loads, rng=rng)
    t = None if task is None else task_matrix(model, params, task, task_point)
    crit = Criterion.from_name(criterion, t)
    stage("information", f"{len(cands.q)} candidates")
    blocks = blocks_for(model, params, cands.q, loads, sigma)
    check_enough_poses(n_poses, blocks, model.tool.n_markers, len(loads), rng)
    stage("relaxation", f"{crit.name} criterion over {len(blocks)} candidates")
    # kept: every sweep over the candidates reads it; room for the refined poses' rows, so the
    # bound's relaxation over candidates and refined poses copies none of it
    room = np.empty((len(blocks) + (n_poses if refine else 0), packed_size(blocks.shape[2])))
    packed = packed_information(blocks, out=room[:len(blocks)])
    relaxed = relax(blocks, crit, progress=stage.iterations("relaxation"), packed=packed)
    stages = {"relaxation": relaxed.to_dict()}
    stage("exchange", f"{n_poses} poses")
    cov = constraints.coverage
    given, moved = home is not None, ""
    home = None if collision is None else home_pose(model.robot, constraints, home)
    if home is not None:
        home, moved = free_home(collision, home, model.robot, given, cands.q)
    keep, replaced, verdict = np.ones(len(cands.q), bool), {}, {}
    pool_q, bounds = cands.q.copy(), constraints.bounds(model.robot)
    for _ in range(_REACH_ROUNDS):
        pool = np.flatnonzero(keep)
        if len(pool) < n_poses:
            raise SolverError(f"only {len(pool)} candidates a program can reach for {n_poses} "
                              f"poses: " + ", ".join(f"{n} {why}" for why, n in replaced.items()))
        every = len(pool) == len(keep)  # no copy of every block when none is removed
        exchanged = exact_design(blocks if every else blocks[pool], n_poses, crit,
                                 relaxed.weights[pool], None,
                                 None if cov is None else cov.bins(cands.q)[pool],
                                 0 if cov is None else cov.min_bins,
                                 packed=packed if every else packed[pool])
        chosen = pool[exchanged.indices]
        if home is None:
            break
        todo = [k for k in chosen if k not in verdict]
        for k, (why, used) in zip(todo, unreachable(collision, pool_q[todo], home, model.robot,
                                                     *bounds)):
            verdict[k], pool_q[k] = why, used
        bad = [k for k in chosen if verdict[k] is not None]
        if not bad:
            break
        for k in bad:
            keep[k] = False
            replaced[verdict[k]] = replaced.get(verdict[k], 0) + 1
    else:
        raise SolverError(f"after {_REACH_ROUNDS} exchanges some chosen poses are still "
                          f"unreachable: " + ", ".join(f"{n} {why}" for why, n in replaced.items())
                          + "; give more candidates, another --home or fewer constraints")
    stages["exchange"] = exchanged.to_dict()
    q, refinement, reverted, design = pool_q[chosen], None, 0, None
    if refine:
        stage("refinement", f"IPOPT on {q.size} joint angles")
        refinement = refine_poses(model, params, loads, sigma, q, feasibility, crit,
                                  collision=collision)
        q, stages["refinement"] = refinement.q, refinement.to_dict()
        if home is not None and refinement.accepted:
            checked = unreachable(collision, q, home, model.robot, *bounds)
            back = np.array([why is not None for why, _ in checked])
            q = np.where(back[:, None], pool_q[chosen], [used for _, used in checked])
            reverted = int(back.sum())
        if refinement.accepted:
            stage("bound", "relaxation with the refined poses as candidates")
            design = blocks_for(model, params, q, loads, sigma)
            packed = room
            packed_information(design, out=packed[len(blocks):])
            relaxed = relax(None, crit, start=np.r_[relaxed.weights, np.zeros(n_poses)],
                            progress=stage.iterations("bound"), packed=packed, screen=True)
    design = blocks_for(model, params, q, loads, sigma) if design is None else design
    m = information(design, np.ones(n_poses))
    value, bound = crit.value(m), relaxed.bound(n_poses)
    p = m.shape[0]
    efficiencies = {crit.name: crit.efficiency(value, bound, p)}
    if not isinstance(crit, DOptimal):
        stage("bound", "D relaxation for the D-efficiency")
        d_bound = relax(None, packed=packed, screen=True).bound(n_poses)
        efficiencies["D"] = DOptimal().efficiency(log_det(m), d_bound, p)
    stage("report")
    reported = [DOptimal(), AOptimal(), EOptimal()] + ([] if t is None else [TaskOptimal(t)])
    criteria = {c.name: c.value(m) for c in reported}
    ratio = equivalence_ratio(None, m / n_poses, crit, packed=packed)
    target = crit.target(p)
    equivalence = {"criterion": crit.name, "statistic": crit.statistic, "target": target,
                   "relaxation": target * relaxed.ratio, "design": target * ratio,
                   "design_efficiency_at_least": 1.0 / ratio}
    randoms = [log_det(information(blocks[rng.choice(len(cands.q), n_poses, replace=False)],
                                   np.ones(n_poses))) for _ in range(_RANDOM_DESIGNS)]
    singular = float(np.mean(~np.isfinite(randoms)))
    equivalent = None
    if np.isfinite(np.median(randoms)):
        equivalent = n_poses * np.exp((log_det(m) - np.median(randoms)) / p)
        versus_random = (f"{n_poses} optimal poses are as precise (D criterion) as "
                         f"{equivalent:.0f} random ones (median of {_RANDOM_DESIGNS} random "
                         f"designs of {n_poses} feasible poses)")
        if singular:
            versus_random += f"; {singular:.0%} of those cannot identify every parameter"
    else:
        versus_random = (f"{singular:.0%} of {_RANDOM_DESIGNS} random designs of {n_poses} "
                         f"feasible poses cannot identify every parameter; these {n_poses} can")
    scale = params.scales[params.free]
    std = np.sqrt(np.diag(np.linalg.inv(m))) * scale
    free = [par for par, f in zip(params.parameters, params.free) if f]
    notes = [versus_random, f"{crit.name} criterion: {crit.words}",
             f"relaxation over {len(packed)} candidates: equivalence ratio {relaxed.ratio:.4g} "
             f"after {relaxed.iterations} iterations; {p} parameters designed for, "
             f"{int((~params.free).sum())} fixed as not identifiable by any candidate"]
    if t is not None:
        notes.append(f"task: predicted RMS position std at the {len(task)} task poses "
                     f"{1000 * np.sqrt(-criteria['task'] / len(task)):.4g} mm "
                     f"(σ = {1000 * sigma:g} mm)")
    coverage = {}
    if cov is not None:
        used = cov.used(q)
        coverage = {"joint": model.robot.joints[cov.joint].name, "bins_used": used,
                    "min_bins": cov.min_bins, "met": len(used) >= cov.min_bins}
    used_constraints = constraints.to_dict(model.robot, model.tool)
    used_constraints["loads"] = [ld.spec() for ld in loads]
    clearances = ()
    if collision is not None:
        stage("clearance", f"distances at the {n_poses} poses")
        clearances = pose_clearances(collision, q)
        used_constraints["collision"] = collision.summary()
        notes.append(collision_note(collision, cands.removed, cands.drawn, clearances))
        notes.append(reachability_note(home, model.robot, replaced, reverted, moved))
        used_constraints["reachability"] = {
            "home": [float(v) for v in home * model.robot.display_factors],
            "replaced": dict(replaced), "refined_reverted": reverted}
    names = [cands.names[k] for k in chosen] if cands.names else None
    cfg = load_configurations(model, params.values, q, loads, names)
    return DesignResult(model.robot, model.tool, model.spec, cfg, crit.name, value, bound,
                        efficiencies[crit.name],
                        {par.name: (float(s * par.display_factor), par.display_unit)
                         for par, s in zip(free, std)}, used_constraints, tuple(notes),
                        efficiencies, criteria, equivalence, cands.to_dict(),
                        {} if refinement is None else refinement.to_dict(), coverage,
                        {"designs": _RANDOM_DESIGNS, "singular_fraction": singular,
                         "equivalent_poses": None if equivalent is None else float(equivalent)},
                        sigma_mm=1000.0 * sigma, clearances=clearances, stages=stages)
