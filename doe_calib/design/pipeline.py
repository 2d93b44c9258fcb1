"""One design pipeline, seven stages, and the goals that plug into it.

candidates → information → relaxation → exchange (poses a program can reach) →
refinement → bound → assessment. :func:`run` owns the order, the candidates
(:func:`draw_candidates`), the reachability of the chosen poses
(:func:`reachable_exchange`) and the progress; a :class:`Goal` owns what
differs between designs, each stage a method that takes the stage results
before it and returns its own: :class:`.optimal.CriterionGoal` (the D, A, E
or task criterion), :class:`.discovery.goal.DiscoveryGoal` (D with effects
detectable, each pose choosing its load case and approach sides) and
:class:`.augment.AugmentGoal` (the poses that add most to a campaign).
"""
from __future__ import annotations

import logging
import time
from dataclasses import dataclass, replace

import numpy as np

from doe_calib.design.candidates.constraints import DesignConstraints
from doe_calib.design.candidates.draw import CandidateSet, feasible_candidates
from doe_calib.design.candidates.feasibility import build_feasibility
from doe_calib.design.candidates.from_file import CandidatePoses, screened_candidates
from doe_calib.design.candidates.reachability import free_home, home_pose, reachable_choice
from doe_calib.design.candidates.sockets import SocketContacts
from doe_calib.io.setting_ranges import positive, whole

log = logging.getLogger(__name__)

#: The stages, in order: ``progress(done, total, note)`` counts them.
STAGES = ("candidates", "information", "relaxation", "exchange", "refinement", "bound",
          "assessment")


@dataclass(frozen=True, eq=False)
class Setting:
    """What every goal designs with: the model and its expected values ``params`` (SI),
    ``n_poses`` to choose, the load cases, the tracker σ per coordinate (m), the
    constraints, the collision model (or None), the home pose asked for (rad, m; None: the
    URDF zero clipped inside the bounds), the random generator and whether to refine."""

    model: object
    params: object
    n_poses: int
    loads: tuple
    sigma: float
    constraints: object
    collision: object = None
    home: np.ndarray | None = None
    rng: object = None
    refine: bool = True

    @classmethod
    def checked(cls, model, n_poses, loads, candidates, sigma, constraints=None,
                collision=None, home=None, rng=None, refine=True, params=None,
                pose: str = "pose") -> "Setting":
        """The setting of a design asked for, its numbers checked and its defaults filled:
        nominal values, the URDF joint limits with their margin, a fresh generator."""
        whole("n_poses", n_poses, 1, pose)
        positive("sigma", sigma, "m")
        if not isinstance(candidates, (CandidatePoses, SocketContacts)):
            whole("candidates", candidates, 1)
        return cls(model, model.nominal() if params is None else params, n_poses, tuple(loads),
                   sigma, DesignConstraints.from_robot(model.robot) if constraints is None
                   else constraints, collision, None if home is None else np.asarray(home, float),
                   np.random.default_rng() if rng is None else rng, refine)


@dataclass(frozen=True, eq=False)
class Candidates:
    """The candidates stage: the pose constraints (:mod:`.feasibility`), the feasible poses,
    and whether they may be refined (not poses read from a file: designed over as they are).
    """

    feasibility: object
    poses: CandidateSet
    refinable: bool


@dataclass(frozen=True)
class Reachability:
    """How the chosen poses were kept reachable from the ``home`` pose (rad, m): chosen poses
    ``replaced`` (reason → count), refined ones ``reverted`` to their candidate, and, when
    the home pose asked for was itself too close, that pose ``moved_from`` (rad, m) and the
    pair ``too_close``."""

    home: np.ndarray
    replaced: dict
    reverted: int = 0
    moved_from: np.ndarray | None = None
    too_close: str = ""

    def to_dict(self, robot) -> dict:
        """``home`` (deg, mm), ``replaced``, ``refined_reverted``, ``moved_from`` (deg, mm)
        and ``too_close``, as design files hold them."""
        f = robot.display_factors
        return {"home": [float(v) for v in self.home * f], "replaced": dict(self.replaced),
                "refined_reverted": self.reverted, "too_close": self.too_close,
                "moved_from": None if self.moved_from is None
                else [float(v) for v in self.moved_from * f]}


@dataclass(frozen=True, eq=False)
class Choice:
    """The exchange stage: the goal's last exchange (``made``, with its ``indices``), the
    ``chosen`` candidates, the candidate poses ``q`` (P, N), each checked one at the angles
    it is reached at (rad, m), and the :class:`Reachability` (None without a collision model).
    """

    made: object
    chosen: np.ndarray
    q: np.ndarray
    reachability: Reachability | None


class Goal:
    """What a design maximises, one method per stage; a stage it lacks returns None.

    ``information(setting, candidates, stage)`` holds ``q`` (the candidate poses) and
    ``pose_of`` (the pose of each candidate it chooses among);
    ``exchange(setting, information, relaxed, allowed, stage)`` chooses among the candidates
    whose pose is ``allowed``; ``assessment(...)`` returns the result.
    """

    #: Each candidate is judged with its own load case (the goal chooses one per pose).
    own_load_case = False

    def relaxation(self, setting, information, stage):
        return None

    def refinement(self, setting, candidates, information, choice, stage):
        return None

    def bound(self, setting, information, relaxed, refined, stage):
        return None


class Stages:
    """Reports each stage as ``progress(done, total, note)`` and logs its duration.

    ``done`` counts the stages begun of :data:`STAGES`, ``total`` is their number,
    ``note`` reads ``stage: what it does``; a stage's iterations report
    ``progress(iteration, None, note)``.
    """

    def __init__(self, progress=None):
        self.progress, self.name, self.start = progress, None, time.perf_counter()

    def __call__(self, name: str, note: str = "") -> None:
        now = time.perf_counter()
        if self.name is not None and name != self.name:
            log.info("design stage %s: %.2f s", self.name, now - self.start)
        if name != self.name:
            self.name, self.start = name, now
        if self.progress is not None:
            self.progress(STAGES.index(name) + 1, len(STAGES), f"{name}: {note}" if note else name)

    def iterations(self, name):
        """The ``progress(iteration, gap)`` of an iterative solver, reported under ``name``."""
        if self.progress is None:
            return None
        return lambda it, gap: self.progress(it, None, f"{name}: iteration {it}, gap {gap:.3g}")


def draw_candidates(setting: Setting, candidates, own_load_case: bool,
                    stage: Stages) -> Candidates:
    """The candidates stage: ``candidates`` random feasible poses, the poses of a file
    screened by the same constraints, or socket contacts (:mod:`.candidates.sockets`),
    plane touches or ballbar positions (its subclasses).

    ``own_load_case``: each candidate is later judged with its own load case (a goal that
    chooses one per pose), so the constraints here leave the load torques out.
    """
    model, constraints = setting.model, setting.constraints
    feasibility = build_feasibility(model, setting.params.values,
                                    replace(constraints, torque_limits=None) if own_load_case
                                    else constraints, setting.loads)
    if isinstance(candidates, CandidatePoses):
        stage("candidates", f"screening the {len(candidates)} poses of {candidates.source}")
        poses = screened_candidates(feasibility, model.robot, candidates, setting.collision)
        return Candidates(feasibility, poses, False)
    if isinstance(candidates, SocketContacts):
        what = {"socket": "in {} sockets", "plane": "on {} planes",
                "ballbar": "about {} ballbar pivots"}[candidates.kind]
        stage("candidates", f"seating the ball {what.format(len(candidates.sockets.names))} at "
                            f"{candidates.per_socket} tool orientations each")
        poses = candidates.draw(feasibility, model, setting.params.values, setting.rng,
                                setting.collision)
        return Candidates(feasibility, poses, False)
    stage("candidates", f"drawing {candidates} feasible poses")
    poses = feasible_candidates(feasibility, model.robot, candidates, setting.rng,
                                setting.collision)
    return Candidates(feasibility, poses, True)


def reachable_exchange(exchange, q, pose_of, setting: Setting) -> Choice:
    """The exchange stage: ``exchange(allowed)`` (the goal's, returning an outcome with
    ``indices``) until every chosen pose is joined to the home pose.

    Without a collision model one exchange over every candidate; with it,
    :func:`.reachability.reachable_choice` removes an unreachable chosen pose and asks
    again. ``q`` (P, N): the candidate poses, rad (m); ``pose_of`` (K,): the pose of each
    candidate the exchange chooses among.
    """
    made = []

    def choose(allowed):
        made.append(exchange(allowed))
        return made[-1].indices

    collision, robot = setting.collision, setting.model.robot
    if collision is None:
        chosen = choose(np.ones(len(q), bool))
        return Choice(made[-1], np.asarray(chosen), q, None)
    asked = home_pose(robot, setting.constraints, setting.home)
    start, too_close = free_home(collision, asked, robot, setting.home is not None, q)
    chosen, used, replaced = reachable_choice(choose, q, pose_of, collision, start, robot,
                                              *setting.constraints.bounds(robot))
    return Choice(made[-1], np.asarray(chosen), used, Reachability(
        start, replaced, 0, asked if too_close else None, too_close))


def constraints_used(setting: Setting, loads, reach: Reachability | None) -> dict:
    """The constraints as used (file units), with the ``loads`` (their specs), the collision
    model and the reachability when checked."""
    model, collision = setting.model, setting.collision
    used = setting.constraints.to_dict(model.robot, model.tool)
    used["loads"] = [ld.spec() for ld in loads]
    if collision is not None:
        used["collision"] = collision.summary()
        used["reachability"] = reach.to_dict(model.robot)
    return used


def run(goal: Goal, setting: Setting, candidates, progress=None):
    """The design of ``goal``: every stage in order, each given the results before it.

    ``candidates``: random feasible candidates to draw, the poses of a file
    (:class:`.from_file.CandidatePoses`) or socket contacts, plane touches or ballbar
    positions (:class:`.candidates.sockets.SocketContacts` and its subclasses);
    ``progress(done, total, note)``, optional.
    Returns the goal's result (:class:`.result.DesignResult`,
    :class:`.augment_result.AugmentResult`, :class:`.contact_result.ContactDesign`).
    """
    stage = Stages(progress)
    drawn = draw_candidates(setting, candidates, goal.own_load_case, stage)
    info = goal.information(setting, drawn, stage)
    relaxed = goal.relaxation(setting, info, stage)
    choice = reachable_exchange(
        lambda allowed: goal.exchange(setting, info, relaxed, allowed, stage),
        info.q, info.pose_of, setting)
    refined = (goal.refinement(setting, drawn, info, choice, stage)
               if setting.refine and drawn.refinable else None)
    bound = goal.bound(setting, info, relaxed, refined, stage)
    return goal.assessment(setting, drawn, info, relaxed, choice, refined, bound, stage)
