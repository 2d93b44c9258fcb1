"""The constraints of one pose as CasADi Functions: checked over candidates, imposed on IPOPT.

``pose_geometry(q) -> (P, N, tau)`` gives the constrained points (flange
origin, markers, each load's centre of mass; base frame, m), the marker
normals (base frame) and the joint torques τ = J_θᵀF of each load
(computed as J_cᵀ f, the transpose Jacobian of the load's centre of mass
times its weight, N·m or N). ``smooth(q) -> g`` stacks every smooth
constraint as rows g ≥ 0 (keep-in, floor, line of sight, load torque).
Keep-out boxes are checked exactly over candidates (signed distance to the
box ≥ clearance) and imposed on IPOPT as the separating plane at the
start pose — linear in the point, conservative, satisfied at the start.
"""
from __future__ import annotations

from dataclasses import dataclass

import casadi as ca
import numpy as np

from doe_calib.design.batch import map_poses
from doe_calib.design.solvers.symbolic import flange_frame, hanging_wrench, symbolic_model

_TOL = 1e-9  # accepted violation in the numeric check (m, cos, relative torque)


@dataclass(frozen=True, eq=False)
class Feasibility:
    """A design's constraints for one pose.

    Attributes
    ----------
    constraints : DesignConstraints
    geometry : casadi.Function
        ``pose_geometry(q) -> (P (3, n_points), N (3, n_markers), tau (N, n_loads))``.
    smooth : casadi.Function
        ``smooth(q) -> g``: rows ≥ 0 when satisfied.
    checked : casadi.Function
        ``checked(q) -> (P, g)``: what :meth:`residuals` reads, in one evaluation of the
        kinematics (no normals or load torques).
    groups : tuple of (str, int, int)
        Constraint name and its rows ``start:stop`` of ``g``.
    clearance : ndarray, shape (n_points,)
        Radius kept around each point, m.
    """

    constraints: object
    geometry: ca.Function
    smooth: ca.Function
    checked: ca.Function
    groups: tuple
    clearance: np.ndarray

    def residuals(self, q: np.ndarray) -> dict:
        """Smallest margin of every constraint at each pose of q (M, N); ≥ 0 when satisfied.

        Units: m for Cartesian and line-of-sight constraints (the latter
        scaled by the distance to the tracker), fraction of the limit for
        load torques.
        """
        points, g = map_poses(self.checked, q)
        g = g[:, :, 0]
        out = {}
        for box in self.constraints.keep_out:
            lo, hi = np.array(box.lower)[:, None], np.array(box.upper)[:, None]
            inside = np.minimum(points - lo, hi - points)  # per axis, < 0 outside the box
            outside = np.sqrt((np.minimum(inside, 0) ** 2).sum(axis=1))
            depth = np.maximum(inside.min(axis=1), 0)
            out[f"keep_out:{box.name}"] = (outside - depth - self.clearance).min(1)
        for name, start, stop in self.groups:
            out[name] = g[:, start:stop].min(axis=1)
        return out

    def feasible(self, q: np.ndarray) -> tuple[np.ndarray, dict]:
        """(mask of the poses satisfying every constraint, name → mask of violators)."""
        violated = {name: r < -_TOL for name, r in self.residuals(q).items()}
        ok = np.ones(len(np.atleast_2d(q)), bool)
        for v in violated.values():
            ok &= ~v
        return ok, violated

    def expressions(self, q, start: np.ndarray):
        """Constraint rows g(q) ≥ 0 for IPOPT (MX or SX q), keep-out planes chosen at ``start``."""
        rows = [self.smooth(q)]
        if self.constraints.keep_out:
            p0 = np.asarray(self.geometry(start)[0])
            points = self.geometry(q)[0]
            for box in self.constraints.keep_out:
                near = np.clip(p0, np.array(box.lower)[:, None], np.array(box.upper)[:, None])
                normal = p0 - near
                length = np.linalg.norm(normal, axis=0)
                if np.any(length <= 0):
                    raise ValueError(f"the start pose is inside keep-out box {box.name!r}")
                normal = normal / length
                rows.append(ca.sum1(ca.DM(normal) * (points - ca.DM(near))).T
                            - ca.DM(self.clearance))
        return ca.vertcat(*rows)


def build_feasibility(model, values, constraints, loads) -> Feasibility:
    """The constraints of a design as Functions of one pose.

    Parameters
    ----------
    model : Model
    values : array_like, shape (P,)
        Parameter values placing the robot and the markers, SI.
    constraints : DesignConstraints
    loads : sequence of LoadCase
    """
    model = symbolic_model(model)
    robot, tool = model.robot, model.tool
    q = ca.SX.sym("q", robot.n_joints)
    values = ca.DM(values)
    rot, origin = flange_frame(model, values, q)
    names = [p.name for p in model.parameters]
    markers = [values[[names.index(f"marker_{m}_{a}") for a in "xyz"]] for m in tool.names]
    coms = [origin + rot @ ca.DM(load.com) for load in loads]
    points = ca.horzcat(origin, *[origin + rot @ u for u in markers], *coms)
    clearance = np.r_[np.zeros(1 + len(markers)), np.full(len(loads), constraints.load_clearance)]
    los = constraints.line_of_sight
    normals = ca.horzcat(*[rot @ ca.DM(n) for n in los.normals]) if los else ca.SX(3, 0)
    torques = ca.horzcat(*[ca.jacobian(c, q).T @ hanging_wrench(rot, load)[:3]
                           for c, load in zip(coms, loads)]) if loads else ca.SX(robot.n_joints, 0)
    geometry = ca.Function("pose_geometry", [q], [points, normals, torques], ["q"],
                           ["P", "N", "tau"])
    rows, groups = [], []

    def group(name, g):
        start = sum(r.numel() for r in rows)
        rows.append(ca.vec(g))
        groups.append((name, start, start + g.numel()))

    r = ca.DM(clearance).T
    if constraints.keep_in is not None:
        lo, hi = ca.DM(constraints.keep_in.lower), ca.DM(constraints.keep_in.upper)
        group("keep_in", ca.vertcat(points - ca.repmat(lo, 1, points.size2()) - ca.repmat(r, 3, 1),
                                    ca.repmat(hi, 1, points.size2()) - points
                                    - ca.repmat(r, 3, 1)))
    if constraints.floor is not None:
        group("floor", points[2, :] - constraints.floor - r)
    if los is not None:
        sight = ca.DM(los.tracker) - points[:, 1:1 + tool.n_markers]
        group("line_of_sight", ca.sum1(normals * sight)
              - np.cos(los.max_incidence) * ca.sqrt(ca.sum1(sight ** 2)))
    if constraints.torque_limits is not None and loads:
        limits = np.asarray(constraints.torque_limits)
        k = np.flatnonzero(np.isfinite(limits)).tolist()
        ratio = torques[k, :] / ca.repmat(ca.DM(limits[k]), 1, len(loads))
        group("load_torque", ca.vertcat(1 - ratio, 1 + ratio))
    g = ca.vertcat(*rows) if rows else ca.SX(0, 1)
    return Feasibility(constraints, geometry, ca.Function("smooth", [q], [g], ["q"], ["g"]),
                       ca.Function("checked", [q], [points, g], ["q"], ["P", "g"]),
                       tuple(groups), clearance)
