"""Programs that move safely: every move checked for collisions, routed round them when it can be.

Each move of the chain of positions (intermediate positions, pre-pose, pose of each
visit) is checked straight in joint space at ≤ 1° steps
(:func:`doe_calib.collision.check_segment`) with the collision model of the load hung
during it (after a load change: the new load, from the previous position). The move to
the first position is not checked; the position itself is.

A colliding move into a visit is first tested for a proof that no path exists
(:func:`doe_calib.collision.blocked_passage`); else routed through one or two
intermediate positions (wrist first or last, through a pose of the program, retract with
the arm joints or turn the wrist as at such a pose; shortest joint travel first, at most
:data:`MAX_ROUTES`), else planned (:func:`doe_calib.collision.plan_move`). A move from a
pre-pose into its pose is never routed. Moves keep the *move* clearance
(:attr:`~doe_calib.collision.CollisionModel.move_margins`); with a tracker in the model
the beam to every marker is checked at every measuring pose and a blocked one refused.
"""
from __future__ import annotations

from dataclasses import dataclass, replace

import numpy as np

from doe_calib.collision import (PlannerSettings, Workspace, blocked_beams, blocked_passage,
                                 check_path, check_segment, plan_move)
from doe_calib.errors import CollisionError
from doe_calib.export.axis_map import AxisMap
from doe_calib.export.program import Waypoint, ascii_text, load_words
from doe_calib.export.sequence import NO_LOAD
from doe_calib.runtime.forked import forked_map

#: Candidate routes tried for one colliding move, shortest first.
MAX_ROUTES = 40
#: Joints (0-based) a retract sets from a free pose: the arm's second and third.
ARM = (1, 2)


@dataclass(frozen=True)
class Collision:
    """A move of a program that collides.

    Attributes
    ----------
    move : int
        1-based number among the moves checked (the first position is move 1).
    words : str
        Where from and where to, under which load.
    fraction : float
        Fraction of the move (0 … 1) at the first pose closer than the clearance.
    q : tuple of float
        The URDF joint values there, deg (mm for prismatic joints).
    pair : str
        The pair found too close, ``"upper_arm_link vs floor"``.
    joint_names : tuple of str
    proof : str
        Why no route can exist, when proven (no route was tried then); else "".
    """

    move: int
    words: str
    fraction: float
    q: tuple
    pair: str
    joint_names: tuple
    proof: str = ""

    def __str__(self) -> str:
        at = ", ".join(f"{n} {v:.1f}" for n, v in zip(self.joint_names, self.q))
        proof = f"; {self.proof}" if self.proof else ""
        return (f"move {self.move}, {self.words}: {self.pair} at {self.fraction:.0%} of the "
                f"move ({at}){proof}")


@dataclass(frozen=True)
class ProgramCheck:
    """The collision check of a program's moves.

    Attributes
    ----------
    visits : tuple of Move
        The program's visits, routed ones with their :attr:`.program.Move.via`.
    moves, samples : int
        Moves checked (the first position counts as one) and poses checked along them.
    routed : tuple of str
        Each routed move in words.
    collisions : tuple of Collision
        Moves that still collide.
    blocked : tuple of str
        Each pose whose tracker beam to a marker is blocked, in words.
    clearance : str
        The clearances the moves kept, in words.
    """

    visits: tuple
    moves: int
    samples: int
    routed: tuple
    collisions: tuple
    blocked: tuple = ()
    clearance: str = ""

    @property
    def free(self) -> bool:
        """No move collides and no beam is blocked."""
        return not self.collisions and not self.blocked

    def summary(self) -> str:
        """One line per finding: how much was checked, each routed move, each collision."""
        kept = f" ({self.clearance})" if self.clearance else ""
        lines = [f"collision check of the program: {self.moves} moves, {self.samples} poses "
                 f"checked at ≤ 1° steps{kept}; {len(self.routed)} routed, "
                 f"{len(self.collisions)} colliding, {len(self.blocked)} beams blocked"]
        lines += [f"routed: {r}" for r in self.routed]
        lines += [f"collides: {c}" for c in self.collisions]
        lines += [f"blocked: {b}" for b in self.blocked]
        return "\n".join(lines)

    def raise_if_colliding(self) -> None:
        """Raise :class:`CollisionError` naming every colliding move and every blocked beam."""
        said = []
        if self.collisions:
            said.append(f"the program would collide in {len(self.collisions)} move(s): "
                        + "; ".join(str(c) for c in self.collisions))
        if self.blocked:
            said.append(f"the tracker's beam is blocked at {len(self.blocked)} pose(s): "
                        + "; ".join(self.blocked))
        if said:
            raise CollisionError(
                "; ".join(said)
                + " — change the design (more clearance, a constraints file, another tracker "
                  "position) or write it anyway with --allow-collisions")


def program_models(loads, build) -> dict:
    """The collision model of each load case (``loads``: LoadCase), keyed by the load in words
    (:data:`.sequence.NO_LOAD`: without payload); ``build(loads)`` → CollisionModel."""
    models = {NO_LOAD: build(())}
    models.update({load_words(load.spec()): build((load,)) for load in loads})
    return models


def _label(m) -> str:
    return f"pose {m.pose}" + (f" (load case {m.case} of {m.n_cases})" if m.n_cases > 1 else "")


def _travel(path) -> float:
    return float(sum(np.max(np.abs(b - a)) for a, b in zip(path[:-1], path[1:])))


def _routes(a, b, safe) -> list:
    """Candidate routes a → b (URDF values): (words, intermediate positions), shortest first."""
    arm = [k for k in ARM if k < len(a)]
    wrist = list(range(max(ARM) + 1, len(a)))
    out = []
    if wrist:
        first = a.copy()
        first[wrist] = b[wrist]
        out.append(("turning the wrist first", [first]))
        first = b.copy()
        first[wrist] = a[wrist]
        out.append(("moving the arm first", [first]))
    for name, p in safe:
        if np.allclose(p, a) or np.allclose(p, b):
            continue
        out.append((f"through pose {name}", [p]))
        for joints, how in ((arm, "retract with the arm joints"),
                            (wrist, "turn the wrist as")):
            if joints:
                ra, rb = a.copy(), b.copy()
                ra[joints], rb[joints] = p[joints], p[joints]
                out.append((f"{how} of pose {name}", [ra, rb]))
    return sorted(out, key=lambda r: _travel([a, *r[1], b]))[:MAX_ROUTES]


def _margins(cm):
    return cm.move_margins or cm.margins


def _route(cm, a, b, pair, safe, ws, planner):
    """``(words, intermediate positions, samples, proof)`` of the first candidate route a → b
    that passes, else of a planned path; words and positions None when none passes; proof
    the Blockage when none can (then none is tried). ``pair``: the straight move's pair."""
    poses = np.array([a, b, *(p for _, p in safe)])
    lower = np.minimum(np.asarray(cm.lower, float), poses.min(axis=0))
    upper = np.maximum(np.asarray(cm.upper, float), poses.max(axis=0))
    blocked = blocked_passage(cm, a, b, _margins(cm), lower, upper, ws)
    if blocked is not None:
        return None, None, 0, blocked
    samples, margins = 0, _margins(cm)
    suspects = [cm.pairs.index(pair)]  # pairs found too close on this move: looked at first
    for words, via in _routes(a, b, safe):
        path = [a, *via, b]
        # a candidate too close on a suspect pair collides: looked for first, on those only
        hit, checked = check_path(cm, path, margins, ws, suspects)
        if hit is None:
            hit, checked = check_path(cm, path, margins, ws)
            if hit is not None:
                suspects.append(cm.pairs.index(hit.pair))
        samples += checked
        if hit is None:
            return words, via, samples, None
    if planner is not None:
        planned = plan_move(cm, a, b, settings=planner, workspace=ws, prove=False)
        if planned is not None:
            return (f"planned (RRT-Connect, {len(planned.via)} intermediate positions)",
                    list(planned.via), samples + planned.samples, None)
    return None, None, samples, None


def check_program(visits, models, robot, axis_map: AxisMap | None = None,
                  route: bool = True, planner: PlannerSettings | bool = True,
                  workers: int | None = None) -> ProgramCheck:
    """Check every move of a program for collisions; route the colliding ones when possible.

    Parameters
    ----------
    visits : sequence of Move
        The program (:func:`.program.moves`).
    models : dict
        Load in words → CollisionModel (:func:`program_models`); a load it does not name
        is checked with the :data:`.sequence.NO_LOAD` model.
    robot : Robot
    axis_map : AxisMap, optional
        Controller values of the intermediate positions from the URDF's.
    route : bool
        Look for intermediate positions round a colliding move.
    planner : PlannerSettings or bool
        True: as each collision model says; False: simple routes only; or these settings.
    workers : int, optional
        Processes (default: the CPUs); the result does not depend on it.

    Examples
    --------
    >>> checked = check_program(moves(design), program_models(loads, build), design.robot)
    ... # doctest: +SKIP
    >>> checked.raise_if_colliding()  # doctest: +SKIP
    """
    axis_map = AxisMap.identity(robot.n_joints) if axis_map is None else axis_map
    factors = robot.display_factors
    names = tuple(robot.joint_names)
    workspaces = {id(cm): Workspace(cm) for cm in models.values()}
    safe = list({m.pose: m.urdf_q for m in visits}.items())
    legs, jobs, previous = [], [], None  # legs: each visit's model, start and first position
    for m in visits:  # every move's check (and route) is known before any is made
        cm = models.get(m.load, models[NO_LOAD])
        first = m.urdf_q if m.urdf_pre is None else m.urdf_pre
        start = first if previous is None else previous
        legs.append((cm, start, first))
        settings = cm.planner if planner is True else (planner or None)
        jobs.append((cm, start, first, route and previous is not None, settings))
        if m.urdf_pre is not None:
            jobs.append((cm, m.urdf_pre, m.urdf_q, False, None))
        previous = m.urdf_q
    # the collision models are not picklable: forked children see them
    done = iter(forked_map(_checked_move, (jobs, safe, workspaces), len(jobs), workers))
    out, routed, collisions, blocked = [], [], [], []
    n_moves = n_samples = 0
    where = None

    def collision(result, qa, qb, words, proof=None):
        q = (qa + result.first * (qb - qa)) * factors
        return Collision(n_moves, words, result.first, tuple(float(v) for v in q),
                         result.pair, names, "" if proof is None else proof.words(names, factors))

    for m, (cm, start, first) in zip(visits, legs):
        to = _label(m) if m.urdf_pre is None else f"pre-pose of {_label(m)}"
        words = (f"first position, {to}" if where is None else f"from {where} to {to}") \
            + f", {m.load}"
        result, (how, via, samples, proof) = next(done)
        n_moves += 1
        n_samples += result.samples + samples
        if via is not None:
            why = ascii_text(f"on the way from {where} to {to}, {how} (straight: "
                             f"{result.pair})")
            m = replace(m, via=tuple(
                Waypoint(axis_map.to_controller(u * factors), u,
                         f"intermediate {k} of {len(via)} {why}") for k, u in enumerate(via, 1)))
            routed.append(f"move {n_moves}, {words}: {how} (straight: {result.pair})")
            result = None
        if result is not None and not result.free:
            collisions.append(collision(result, start, first, words, proof))
        if m.urdf_pre is not None:
            words = f"from {to} into {_label(m)}, {m.load}"
            result, _ = next(done)
            n_moves += 1
            n_samples += result.samples
            if not result.free:
                collisions.append(collision(result, m.urdf_pre, m.urdf_q, words))
        for b in (blocked_beams(cm, m.urdf_q, workspaces[id(cm)]) if m.measures else ()):
            blocked.append(f"{_label(m)}, {m.load}: {b}")  # beams matter where it measures
        where = _label(m)
        out.append(m)
    cm = models[NO_LOAD]
    return ProgramCheck(tuple(out), n_moves, n_samples, tuple(routed), tuple(collisions),
                        tuple(dict.fromkeys(blocked)),
                        f"moves keep {1000 * cm.move_clearance:g} mm, "
                        f"{1000 * cm.move_self_clearance:g} mm between links; poses "
                        f"{1000 * cm.clearance:g} mm")


def _checked_move(shared, i: int):
    """Job ``i``'s straight check and (route words, intermediate positions, samples, proof)."""
    jobs, safe, workspaces = shared
    cm, qa, qb, routable, settings = jobs[i]
    ws = workspaces[id(cm)]
    result = check_segment(cm, qa, qb, _margins(cm), workspace=ws)
    if result.free or not routable:
        return result, (None, None, 0, None)
    return result, _route(cm, qa, qb, result.pair, safe, ws, settings)
