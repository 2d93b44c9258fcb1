"""Continuous refinement: IPOPT moves the N poses' joint angles together.

The exact design's poses are the start; the objective is log Φ of the
information M(q_1 … q_N) = Σ_i pose_information(q_i) (:mod:`.symbolic`,
loads' wrenches functions of q), under the joint bounds and the pose
constraints (:mod:`.feasibility`). Coverage is kept by holding one pose of
each required bin inside its bin. Each refined pose is re-checked
numerically, exactly (constraints and, with a collision model, the
clearance); one that fails steps back toward its start (halfway, a quarter
of the way …, else the start itself). The refined design is kept only if it
improves the criterion.
"""
from __future__ import annotations

import logging
import time

import casadi as ca
import numpy as np

from doe_calib.collision import too_close
from doe_calib.design.criteria import Criterion
from doe_calib.design.solvers.outcome import DesignOutcome
from doe_calib.design.solvers.symbolic import log_criterion, pose_information

log = logging.getLogger(__name__)

_MARGIN = 1e-7  # rows g ≥ this in IPOPT, so its tolerance never leaves g < 0
_STEPS_BACK = (0.5, 0.25, 0.125, 0.0625)  # fractions of the move kept when a pose fails


def _admissible(feasibility, collision, q: np.ndarray) -> np.ndarray:
    """Mask of the poses of q (M, N) meeting every constraint and keeping their clearance."""
    ok, _ = feasibility.feasible(q)
    if collision is not None:
        ok &= too_close(collision, q) < 0
    return ok


def step_back(q0: np.ndarray, q1: np.ndarray, admissible) -> tuple[np.ndarray, int]:
    """Poses q1 (M, N), each failing one moved back toward its admissible start q0.

    ``admissible(q) -> mask`` re-checks poses; a failing pose is tried at
    the fractions :data:`_STEPS_BACK` of its move, and is its start when none
    passes. Returns the poses and how many stepped back.
    """
    out = q1.copy()
    bad = np.flatnonzero(~admissible(q1))
    for i in bad:
        tries = q0[i] + np.array(_STEPS_BACK)[:, None] * (q1[i] - q0[i])
        ok = np.flatnonzero(admissible(tries))
        out[i] = tries[ok[0]] if len(ok) else q0[i]
    return out, len(bad)


def _bounds(q0, constraints, robot):
    """Joint bounds of every pose; one pose per required coverage bin held in its bin."""
    lo, hi = constraints.bounds(robot)
    lbx, ubx = np.tile(lo, (len(q0), 1)), np.tile(hi, (len(q0), 1))
    cov = constraints.coverage
    if cov is not None:
        bins = cov.bins(q0)
        for b in cov.used(q0):
            i = int(np.flatnonzero(bins == b)[0])
            lbx[i, cov.joint] = max(lbx[i, cov.joint], cov.edges[b])
            ubx[i, cov.joint] = min(ubx[i, cov.joint], cov.edges[b + 1])
    return lbx, ubx


def _groups(model, params, loads, sigma, n, variants):
    """(pose_information Function, pose indices) per distinct (load cases, approach sides)."""
    if variants is None:
        return [(pose_information(model, params, loads, sigma), list(range(n)))]
    keys = {}
    for i, (cases, approach) in enumerate(variants):
        key = (tuple(cases), tuple(float(a) for a in approach))
        keys.setdefault(key, []).append(i)
    return [(pose_information(model, params, list(cases), sigma, approach), idx)
            for (cases, approach), idx in keys.items()]


def _information(groups, q: np.ndarray, p: int) -> np.ndarray:
    """Σ_i M(q_i) (p, p) of the poses q (n, N), numerically."""
    return sum(np.array(info.map(len(idx))(q[idx].T)).reshape(-1, len(idx), p).sum(axis=1)
               for info, idx in groups)


def refine(model, params, loads, sigma: float, q0: np.ndarray, feasibility,
           criterion="D", max_iterations: int = 300, collision=None,
           variants=None) -> DesignOutcome:
    """Optimise the poses q0 (N, n_joints) jointly with IPOPT (L-BFGS Hessian).

    Parameters
    ----------
    model : Model
    params : ParameterSet
        Expected values and the free parameters designed for.
    loads : sequence of LoadCase
    sigma : float
        Tracker σ per coordinate, m.
    q0 : ndarray, shape (N, n_joints)
        Start poses (the exact design), rad/m; they satisfy every constraint.
    feasibility : Feasibility
    criterion : {"D", "A", "E"} or Criterion
    collision : CollisionModel, optional
        Refined poses closer than its clearances step back (:func:`step_back`).
    variants : sequence of (sequence of load cases, array_like (n_joints,)), optional
        Per pose, the load cases it is measured under (besides unloaded) and the
        approach sides it is reached from, when they differ between poses (a
        discovery design); default every pose under ``loads``, approach 0.

    Returns
    -------
    DesignOutcome
        Stage ``refinement``: ``q`` the poses kept (the refined ones if
        ``accepted``, else q0), ``value`` and ``start_value`` their criterion,
        ``status`` IPOPT's return status or why the result was not kept.
    """
    crit = Criterion.from_name(criterion)
    t0 = time.perf_counter()
    n, dof = q0.shape
    groups = _groups(model, params, loads, sigma, n, variants)
    p = groups[0][0].size1_out(0)
    m0 = _information(groups, q0, p)
    start_value = crit.value(m0)
    objective = log_criterion(crit, p, reference=crit.reference(m0))
    q = ca.MX.sym("q", dof, n)
    m = sum(info.map(len(idx))(q[:, idx]) @ ca.repmat(ca.DM.eye(p), len(idx), 1)
            for info, idx in groups)
    g = ca.vertcat(*[feasibility.expressions(q[:, i], q0[i]) for i in range(n)])
    lbx, ubx = _bounds(q0, feasibility.constraints, model.robot)
    solver = ca.nlpsol("refine", "ipopt", {"x": ca.vec(q), "f": -objective(m), "g": g},
                       {"print_time": False, "ipopt.print_level": 0, "ipopt.sb": "yes",
                        "ipopt.hessian_approximation": "limited-memory",
                        "ipopt.max_iter": max_iterations, "ipopt.tol": 1e-8,
                        "ipopt.bound_relax_factor": 0.0})
    sol = solver(x0=q0.ravel(), lbx=lbx.ravel(), ubx=ubx.ravel(), lbg=_MARGIN, ubg=np.inf)
    stats = solver.stats()
    status, iterations = str(stats["return_status"]), int(stats["iter_count"])
    q1 = np.clip(np.array(sol["x"]).reshape(n, dof), lbx, ubx)
    q1, stepped = step_back(q0, q1, lambda q: _admissible(feasibility, collision, q))
    if stepped:
        status += (f"; {stepped} pose(s) failing the re-check "
                   f"({'constraints or clearance' if collision is not None else 'constraints'}) "
                   f"stepped back toward the start")
    m1 = _information(groups, q1, p)
    value = crit.value(m1)
    accepted = bool(value > start_value)
    if not accepted:
        status += "; not kept: the criterion did not improve"
    log.info("refinement: %s after %d iterations, %.6g → %.6g", status, iterations, start_value,
             value)
    return DesignOutcome("refinement", crit, np.ones(n), float(value if accepted else start_value),
                         iterations, status, p, q=q1 if accepted else q0,
                         start_value=float(start_value), accepted=accepted,
                         seconds=time.perf_counter() - t0, stepped_back=stepped)
