"""The D-, A-, E- or task-optimal design: the criterion goal of the design pipeline.

Its stages (:mod:`.pipeline`): the information blocks of the candidates, the
convex relaxation of the criterion (its certified bound), the exact exchange,
the continuous IPOPT refinement, the bound recomputed with the refined poses
among the candidates, and the assessment: efficiencies, the equivalence-theorem
check and the comparison with random designs of the same size.
"""
from __future__ import annotations

from dataclasses import dataclass, replace

import numpy as np

from doe_calib.design.candidates.clearances import pose_clearances
from doe_calib.design.candidates.constraints import DesignConstraints
from doe_calib.design.candidates.from_file import CandidatePoses
from doe_calib.design.candidates.reachability import revert_unreachable
from doe_calib.design.criteria import (AOptimal, Criterion, DOptimal, EOptimal, TaskOptimal,
                                       check, log_det)
from doe_calib.design.pipeline import Goal, Setting, constraints_used, run
from doe_calib.design.predicted_std import design_std
from doe_calib.design.problem import (blocks_for, candidate_information, check_enough_poses,
                                      design_parameters, load_configurations, task_matrix)
from doe_calib.design.result import (BoundRelaxation, Coverage, DesignResult, Equivalence,
                                     RandomDesigns)
from doe_calib.design.solvers.exchange import exact_design
from doe_calib.design.solvers.pose_refinement import refine as refine_poses
from doe_calib.design.solvers.relaxation import (equivalence_ratio, information,
                                                 packed_information, relax)
from doe_calib.errors import OptionError, SolverError

#: Random designs of the same size the design is compared with.
RANDOM_DESIGNS = 100


@dataclass(frozen=True, eq=False)
class CriterionInformation:
    """The information stage of a criterion design: the parameters designed for (those no
    candidate identifies fixed), the criterion, the task matrix T (or None), each
    candidate's scaled, weighted rows ``blocks`` (K, r, p) and its information ``packed``
    (:func:`.relaxation.packed_information`: every sweep over the candidates reads it),
    kept at the start of ``room``, which holds the refined poses' rows after it so that the
    bound's relaxation copies none of it; the candidate poses ``q`` (K, N), rad (m)."""

    params: object
    criterion: Criterion
    task: np.ndarray | None
    blocks: np.ndarray
    packed: np.ndarray
    room: np.ndarray
    q: np.ndarray
    pose_of: np.ndarray


@dataclass(frozen=True, eq=False)
class Refined:
    """The refinement stage: IPOPT's outcome and the poses kept, rad (m), those unreachable
    from home back at their candidate (``reverted`` of them)."""

    outcome: object
    q: np.ndarray
    reverted: int = 0


@dataclass(frozen=True, eq=False)
class Bound:
    """The bound stage: the relaxation that certifies the bound, the information it read
    (``packed``), and the design's blocks when they were computed for it."""

    relaxed: object
    packed: np.ndarray
    design: np.ndarray | None = None


@dataclass(frozen=True)
class CriterionGoal(Goal):
    """Maximise a criterion of the N poses' information (D, A, E or task)."""

    criterion: object = "D"
    task: object = None
    task_point: tuple = (0.0, 0.0, 0.0)

    def information(self, setting, candidates, stage) -> CriterionInformation:
        model, n_poses, loads = setting.model, setting.n_poses, setting.loads
        q = candidates.poses.q
        if len(q) < n_poses:
            raise SolverError(f"only {len(q)} feasible candidates for {n_poses} poses")
        params = design_parameters(model, setting.params, q, loads, rng=setting.rng)
        t = None if self.task is None else task_matrix(model, params, self.task,
                                                        self.task_point)
        crit = Criterion.from_name(self.criterion, t)
        stage("information", f"{len(q)} candidates")
        blocks, room = candidate_information(
            model, params, q, loads, setting.sigma,
            n_poses if setting.refine and candidates.refinable else 0)
        check_enough_poses(n_poses, blocks, model.tool.n_markers, len(loads), setting.rng)
        return CriterionInformation(params, crit, t, blocks, room[:len(blocks)], room, q,
                                    np.arange(len(q)))

    def relaxation(self, setting, info, stage):
        stage("relaxation", f"{info.criterion.name} criterion over {len(info.blocks)} "
                            f"candidates")
        return relax(info.blocks, info.criterion, progress=stage.iterations("relaxation"),
                     packed=info.packed)

    def exchange(self, setting, info, relaxed, allowed, stage):
        n_poses, cov = setting.n_poses, setting.constraints.coverage
        stage("exchange", f"{n_poses} poses")
        pool = np.flatnonzero(allowed)
        if len(pool) < n_poses:
            raise SolverError(f"only {len(pool)} candidates a program can reach for "
                              f"{n_poses} poses")
        return exact_design(info.blocks, n_poses, info.criterion, relaxed.weights, None,
                            None if cov is None else cov.bins(info.q),
                            0 if cov is None else cov.min_bins, packed=info.packed, among=pool,
                            workers=None)

    def refinement(self, setting, candidates, info, choice, stage) -> Refined:
        model, robot, collision = setting.model, setting.model.robot, setting.collision
        start = choice.q[choice.chosen]
        stage("refinement", f"IPOPT on {start.size} joint angles")
        outcome = refine_poses(model, info.params, setting.loads, setting.sigma, start,
                               candidates.feasibility, info.criterion, collision=collision)
        q, reverted = outcome.q, 0
        if choice.reachability is not None and outcome.accepted:
            q, reverted = revert_unreachable(collision, q, start, choice.reachability.home,
                                             robot, setting.constraints)
        return Refined(outcome, q, reverted)

    def bound(self, setting, info, relaxed, refined, stage) -> Bound:
        if refined is None or not refined.outcome.accepted:
            return Bound(relaxed, info.packed)
        stage("bound", "relaxation with the refined poses as candidates")
        design = blocks_for(setting.model, info.params, refined.q, setting.loads, setting.sigma)
        packed_information(design, out=info.room[len(info.blocks):])
        relaxed = relax(None, info.criterion,
                        start=np.r_[relaxed.weights, np.zeros(setting.n_poses)],
                        progress=stage.iterations("bound"), packed=info.room, screen=True)
        return Bound(relaxed, info.room, design)

    def assessment(self, setting, candidates, info, relaxed, choice, refined, bound,
                   stage) -> DesignResult:
        model, n_poses, crit, params = setting.model, setting.n_poses, info.criterion, info.params
        q = choice.q[choice.chosen] if refined is None else refined.q
        design = (blocks_for(model, params, q, setting.loads, setting.sigma)
                  if bound.design is None else bound.design)
        m = information(design, np.ones(n_poses))
        value, limit = crit.value(m), bound.relaxed.bound(n_poses)
        p = m.shape[0]
        efficiencies = {crit.name: crit.efficiency(value, limit, p)}
        if not isinstance(crit, DOptimal):
            stage("bound", "D relaxation for the D-efficiency")
            d_bound = relax(None, packed=bound.packed, screen=True).bound(n_poses)
            efficiencies["D"] = DOptimal().efficiency(log_det(m), d_bound, p)
        stage("assessment")
        reported = [DOptimal(), AOptimal(), EOptimal()] + ([] if info.task is None
                                                           else [TaskOptimal(info.task)])
        ratio = equivalence_ratio(None, m / n_poses, crit, packed=bound.packed)
        target = crit.target(p)
        versus = RandomDesigns.of([log_det(information(
            info.blocks[setting.rng.choice(len(info.q), n_poses, replace=False)],
            np.ones(n_poses))) for _ in range(RANDOM_DESIGNS)], log_det(m), n_poses, p)
        reach = choice.reachability
        if reach is not None and refined is not None:
            reach = replace(reach, reverted=refined.reverted)
        cands, constraints = candidates.poses, constraints_used(setting, setting.loads, reach)
        clearances = ()
        if setting.collision is not None:
            stage("assessment", f"clearances at the {n_poses} poses")
            clearances = pose_clearances(setting.collision, q)
        names = [cands.names[k] for k in choice.chosen] if cands.names else None
        stages = {"relaxation": relaxed.to_dict(), "exchange": choice.made.to_dict()}
        if refined is not None:
            stages["refinement"] = refined.outcome.to_dict()
        return DesignResult(
            robot=model.robot, tool=model.tool, model=model.spec,
            configurations=load_configurations(model, params.values, q, setting.loads, names),
            criterion=crit.name, value=value, bound=limit, efficiency=efficiencies[crit.name],
            predicted_std=design_std(params, m), constraints=constraints,
            efficiencies=efficiencies, criteria={c.name: c.value(m) for c in reported},
            equivalence=Equivalence(crit.name, crit.statistic, target,
                                    target * bound.relaxed.ratio, target * ratio, 1.0 / ratio),
            candidates=cands.count(), coverage=_coverage(setting, q),
            versus_random=versus,
            sigma_mm=1000.0 * setting.sigma, clearances=clearances, outcomes=stages,
            bound_relaxation=BoundRelaxation(
                len(bound.packed), bound.relaxed.ratio, bound.relaxed.iterations,
                int((~params.free).sum()), 0 if info.task is None else len(info.task) // 3))


def _coverage(setting, q) -> Coverage | None:
    """Bins of the coverage joint used by the poses (None without a coverage constraint)."""
    cov = setting.constraints.coverage
    if cov is None:
        return None
    used = cov.used(q)
    return Coverage(setting.model.robot.joints[cov.joint].name, used, cov.min_bins,
                    len(used) >= cov.min_bins)


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
        named poses (:func:`.from_file.read_candidates`: taught, known-safe
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
    progress : callable(done, total, note), optional
        Stages begun of :data:`.pipeline.STAGES` (total None for a stage's iterations)
        and what the stage does.
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
    discovery : DiscoveryGoal, optional
        Design to discover effects (:mod:`.goal`), D criterion only.
    """
    if isinstance(criterion, TaskOptimal):
        raise OptionError("ask for the task criterion by name, criterion=\"task\", with task= "
                          "poses: its matrix depends on the parameters designed for")
    check(criterion, task)
    if discovery is not None and criterion != "D":
        raise OptionError(f"--detect-size and --load-directions designs maximise the D "
                          f"criterion; got --criterion {criterion}")
    setting = Setting.checked(model, n_poses, loads, candidates, sigma, constraints, collision,
                              home, rng, refine, params)
    goal = CriterionGoal(criterion, task, task_point) if discovery is None else discovery
    return run(goal, setting, candidates, progress)
