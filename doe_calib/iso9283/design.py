"""The ISO 9283 pose test of a robot: its cube, its five poses and the cycles that visit them.

The cube (ISO 9283 §6) is axis-aligned in the robot base frame (the URDF root). Given, its
five test points (:func:`~.standard.cube_points`) are reached by inverse kinematics
from the random configurations whose TCP lies nearest its centre, each tried in turn.
Searched, it is the largest found over random centres: each candidate configuration's
TCP is a centre, and the edge grows by bisection while the robot still reaches the five
points at that configuration's flange orientation (a robot of fewer than 6 joints: the
positions only) inside the joint limits, with the clearances of the collision check when
one is given (the robot, its tool and load, the cell; each pose on its own) and every
tracker beam free when it places a tracker, and the cube, as a box, stays above the
floor, inside the keep-in box and out of the keep-out boxes of the constraints. The moves
between the poses are not searched: ``export`` checks them.

Inverse kinematics is the compensation's problem (:mod:`doe_calib.compensation.nlp`) on
the nominal model (base and markers only), or on an identification result's model and
parameters, its TCP marker the identified one, without load (the compensation's program
accounts for it); the base at the tracker origin, so that the tracker frame is the robot
base frame: the joint values nearest the candidate's that put the TCP on the point.
"""
from __future__ import annotations

import math

import numpy as np

from doe_calib.collision import blocked_beams, check_segment
from doe_calib.compensation.compensate import rotation_angle, tcp_point
from doe_calib.compensation.nlp import build_problem
from doe_calib.design.candidates.constraints import DesignConstraints
from doe_calib.design.result import DesignResult
from doe_calib.errors import OptionError
from doe_calib.estimation.predict import result_model
from doe_calib.io.measurements import Configurations
from doe_calib.iso9283.plan import IsoPlan, visit_id
from doe_calib.iso9283.predicted import predicted_accuracy
from doe_calib.iso9283.standard import POSES, cube_points, roll_pitch_yaw
from doe_calib.model.loads import hanging_mass_wrench
from doe_calib.model.marker_model import build_model

#: Random configurations whose TCP is a candidate centre (or a seed for a cube given).
CANDIDATES = 200
#: Bisection steps of the edge, from 0 to the chain's length: the edge found is within
#: 2⁻¹⁰ of that length below the largest reachable from the centre.
BISECTIONS = 10
#: Largest error (m, rad) of a test point reached.
REACHED = 1e-9


class _Reach:
    """Inverse kinematics of the robot's TCP, within the joint bounds: the nominal robot, or
    the one ``result`` identified (its base at the tracker origin)."""

    def __init__(self, robot, tool, tcp: str, lower, upper, is_free=None, result=None):
        if result is None:
            self.model = build_model(robot, tool, "")
            self.values = self.model.nominal().values
            self.point = tool.position_array[tool.index(tcp)]
        else:
            self.model, params = result_model(result)
            base = params.index("base")
            self.values = params.values.copy()
            self.values[base] = self.model.nominal().values[base]
            self.point = tcp_point(params, tcp)[0]
        self.problem = build_problem(self.model, position_only=robot.n_joints < 6)
        self.env = Configurations.from_arrays(np.zeros((1, robot.n_joints))).env[0]
        self.lower, self.upper = lower, upper
        self.is_free = is_free

    def solve(self, target, rotation, seed) -> np.ndarray | None:
        """Joint values (N,) nearest ``seed`` that put the TCP on ``target`` (m) with the
        flange at ``rotation``; None when not reached to :data:`REACHED` or not free."""
        args = (np.zeros(6), self.env, self.values, self.point)
        p = self.problem.nlp_parameters(target, rotation, *args, seed)
        sol = self.problem.solver(x0=seed, p=p, lbx=self.lower, ubx=self.upper, lbg=0.0,
                                  ubg=0.0)
        q = np.clip(np.asarray(sol["x"]).ravel(), self.lower, self.upper)
        e_pos, e_rot = self.problem.error(q, *args, target, rotation)
        bad = float(np.linalg.norm(np.asarray(e_pos)))
        if not self.problem.position_only:  # the true angle: sin θ · axis is 0 at θ = π too
            bad = max(bad, rotation_angle(e_rot, rotation, self.flange(q)))
        if bad >= REACHED or (self.is_free is not None and not self.is_free(q)):
            return None
        return q

    def flange(self, q) -> np.ndarray:
        """The flange's rotation (3, 3) at joint values ``q`` (N,), base frame, no load."""
        return np.asarray(self.model.flange(q, np.zeros(6), self.env, self.values)[0])

    def cube(self, centre, edge: float, rotation, seed) -> dict | None:
        """Pose → joint values reaching the five test points of the cube; None if one fails."""
        out = {}
        for pose, target in cube_points(centre, edge).items():
            out[pose] = self.solve(target, rotation, seed)
            if out[pose] is None:
                return None
        return out


def _in_cell(centre, edge: float, constraints: DesignConstraints) -> bool:
    """Whether the cube, as a box, keeps above the floor, inside keep-in, out of keep-out."""
    lo, hi = np.asarray(centre) - edge / 2, np.asarray(centre) + edge / 2
    if constraints.floor is not None and lo[2] < constraints.floor:
        return False
    box = constraints.keep_in
    if box is not None and (np.any(lo < box.lower) or np.any(hi > box.upper)):
        return False
    return not any(np.all(lo < b.upper) and np.all(hi > b.lower) for b in constraints.keep_out)


def _largest(reach, centres, rotations, seeds, constraints, top: float) -> tuple:
    """(edge, centre index, joint values) of the largest cube over the candidate centres."""
    best = (0.0, None, None)
    for k, (centre, rot, seed) in enumerate(zip(centres, rotations, seeds)):
        # a centre that cannot hold the best cube so far is passed over: a larger cube
        # there is almost never reached when a smaller one is not
        lo = best[0]
        found = reach.cube(centre, lo, rot, seed) if lo > 0 and _in_cell(
            centre, lo, constraints) else None
        if lo > 0 and found is None:
            continue
        hi = top
        for _ in range(BISECTIONS):
            mid = 0.5 * (lo + hi)
            q = reach.cube(centre, mid, rot, seed) if _in_cell(centre, mid, constraints) \
                else None
            lo, hi, found = (mid, hi, q) if q is not None else (lo, mid, found)
        if found is not None and lo > best[0]:
            best = (lo, k, found)
    return best


def design_test(robot, tool, tcp: str, load=None, constraints: DesignConstraints | None = None,
                cube: tuple | None = None, cycles: int = 30, seed: int = 0,
                collision=None, result=None) -> tuple:
    """The ISO 9283 pose test as a design: ``P1-01`` … ``P5-<cycles>`` in cycle order.

    Parameters
    ----------
    robot, tool : Robot, Tool
    tcp : str
        The marker whose position is tested.
    load : LoadCase, optional
        The load carried through the whole test (each visit's wrench is its weight).
    constraints : DesignConstraints, optional
        Joint limits (with margin) and Cartesian constraints (default: the URDF's limits).
    cube : tuple, optional
        ``(centre (3,), edge)``, m, robot base frame; default: searched (module notes).
    cycles : int
    seed : int
        Of the random candidate configurations.
    collision : CollisionModel, optional
        The cell with the load (:func:`doe_calib.collision.build_collision_model`): each
        test pose keeps its clearances and the tracker's beams; None: not checked.
    result : IdentificationResult, optional
        The poses are reached on its model (module notes), and the plan holds the accuracy
        it predicts after compensation (:mod:`.predicted`).

    Returns
    -------
    tuple of (DesignResult, IsoPlan)
        The design (its ``constraints`` name the load of every row) and the plan, its
        ``"iso9283"`` block (:mod:`.plan`).

    Raises
    ------
    OptionError
        An unknown TCP marker, a cube given that is not reached (or not free), or no cube
        found.

    Examples
    --------
    >>> from doe_calib import Robot, Tool, examples
    >>> design, plan = design_test(Robot.from_urdf(examples.ROBOT_URDF),
    ...                            Tool.from_yaml(examples.TOOL_YAML), "A", cycles=2,
    ...                            cube=([1.5, 0.0, 1.4], 0.4))  # doctest: +SKIP
    >>> design.configurations.pose[:6]  # doctest: +SKIP
    ('P1-01', 'P2-01', 'P3-01', 'P4-01', 'P5-01', 'P1-02')
    """
    if tcp not in tool.names:
        raise OptionError(f"--tcp {tcp!r}: no such marker in the tool; markers: "
                          f"{', '.join(tool.names)}")
    constraints = constraints or DesignConstraints.from_robot(robot)
    lower, upper = constraints.bounds(robot)
    is_free = None if collision is None else (
        lambda q: check_segment(collision, q, q).free and not blocked_beams(collision, q))
    reach = _Reach(robot, tool, tcp, lower, upper, is_free, result)
    which = "nominal" if result is None else "identified"
    rng = np.random.default_rng(seed)
    seeds = rng.uniform(lower, upper, (CANDIDATES, robot.n_joints))
    rot, origin = robot.flange_poses(seeds)
    centres = origin + rot @ reach.point
    if cube is None:
        edge, k, q = _largest(reach, centres, rot, seeds, constraints,
                              float(robot.link_lengths.sum()))
        if k is None:
            raise OptionError("no cube found whose five test points the robot reaches"
                              + (" free of collisions" if collision else "")
                              + ": give one with --cube")
        centre = centres[k]
        chosen = (f"the largest of {CANDIDATES} random centres (seed {seed}) whose five test "
                  f"points the {which} robot reaches at one flange orientation"
                  + (", free of collisions" if collision else ""))
    else:
        centre, edge = np.asarray(cube[0], float), float(cube[1])
        q = None
        for k in np.argsort(np.linalg.norm(centres - centre, axis=1)):
            q = reach.cube(centre, edge, rot[k], seeds[k])
            if q is not None:
                break
        if q is None:
            raise OptionError(f"the {which} robot does not reach the five test points of the "
                              f"cube given at one flange orientation"
                              f"{' free of collisions' if collision else ''} from any of "
                              f"{CANDIDATES} starts: move or shrink it")
        chosen = f"given; the {which} robot reaches its five test points"
    used = constraints.to_dict(robot, tool) if constraints.source else {}
    if collision is not None:
        used["collision"] = collision.summary()
    return _design(robot, tool, reach, q, centre, edge, chosen, tcp, load, used, cycles, result)


def _design(robot, tool, reach, q, centre, edge, chosen, tcp, load, used, cycles, result):
    q_test = np.array([q[p] for p in POSES])
    flange_rot = np.array([reach.flange(x) for x in q_test])
    points = cube_points(centre, edge)
    wrench = np.zeros((len(POSES), 6)) if load is None else hanging_mass_wrench(
        reach.model, reach.values, q_test, load.mass, load.com)
    predicted = {} if result is None else predicted_accuracy(
        reach.model, result, Configurations.from_arrays(q_test, wrench), tcp, POSES, cycles)
    plan = IsoPlan({p: 1000.0 * points[p] for p in POSES},
                    dict(zip(POSES, np.degrees(roll_pitch_yaw(flange_rot)))), tcp,
                    {"centre_mm": (1000.0 * np.asarray(centre)).tolist(),
                     "edge_mm": 1000.0 * edge, "chosen": chosen},
                    "" if load is None else load.spec(), cycles, predicted)
    ids = [visit_id(p, c) for c in range(1, cycles + 1) for p in POSES]
    cfg = Configurations.from_arrays(np.tile(q_test, (cycles, 1)), np.tile(wrench, (cycles, 1)),
                                     pose=ids)
    if load is not None and load.mass > 0:
        used = {**used, "loads": [load.spec()], "row_loads": [load.spec()] * len(ids)}
    design = DesignResult(
        robot=robot, tool=tool, model="", configurations=cfg, criterion="ISO 9283",
        value=math.nan, bound=math.nan, efficiency=math.nan, predicted_std={},
        constraints=used, given_notes=(
            f"ISO 9283 pose test: cube of edge {1000 * edge:.1f} mm centred at "
            f"{', '.join(f'{1000 * v:.1f}' for v in centre)} mm (base frame), {chosen}; "
            f"P1 … P5 visited {cycles} times in that order",))
    return design, plan
