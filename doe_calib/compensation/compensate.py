"""Numeric compensation: targets in, compensated joint values and their predicted accuracy out.

Takes the Functions of :mod:`.nlp` and arrays; builds no expression.
"""
from __future__ import annotations

import logging
import warnings

import numpy as np

from doe_calib.compensation.accuracy import row_accuracy, unseen_warning
from doe_calib.compensation.flags import MAX_SHIFT, row_shift_flags
from doe_calib.compensation.nlp import CompensationProblem, build_problem
from doe_calib.compensation.result import CompensationResult
from doe_calib.compensation.targets import TRACKER
from doe_calib.errors import ConvergenceWarning, DataWarning, IdentifiabilityWarning, OptionError
from doe_calib.estimation.identifiability import blind_motion_words
from doe_calib.estimation.measured_region import outside_flags
from doe_calib.estimation.sockets import frame_unseen_part, frame_words, from_contacts
from doe_calib.estimation.unseen import measured_markers, unseen_part
from doe_calib.model.evaluation import evaluate

log = logging.getLogger(__name__)

#: Position error (m) and rotation error (rad) above which a row is not reached.
POSITION_TOLERANCE = 1e-6
ROTATION_TOLERANCE = 1e-6
_SOLVED = ("Solve_Succeeded", "Solved_To_Acceptable_Level")


def tcp_point(parameters, tcp) -> tuple[np.ndarray, str | None]:
    """The TCP in the flange frame (m) and its marker name (None for a point), from ``tcp``:
    a marker name of ``parameters`` or a point (3,) in the flange frame, m."""
    if isinstance(tcp, str):
        names = [f"marker_{tcp}_{a}" for a in "xyz"]
        if not all(n in parameters.names for n in names):
            markers = sorted({n.split("_")[1] for n in parameters.names
                              if n.startswith("marker_")})
            raise OptionError(f"--tcp {tcp!r}: no such marker in the result; markers: "
                              f"{', '.join(markers)}, or give X,Y,Z in mm (flange frame)")
        return np.array([parameters[n] for n in names]), tcp
    return np.asarray(tcp, float).reshape(3), None


def nominal_targets(model, parameters, configurations, tcp) -> tuple[np.ndarray, np.ndarray]:
    """Where the nominal robot (no wrench), placed by the identified base, puts the TCP:
    x (M, 3) m and R (M, 3, 3), tracker frame."""
    values = model.nominal().values.copy()
    base = parameters.index("base")
    values[base] = parameters.values[base]
    cfg = configurations
    unloaded = type(cfg).from_arrays(cfg.q, None, cfg.env, cfg.pose)
    rot, origin = evaluate(model.flange, unloaded, values)
    return origin[:, :, 0] + rot @ tcp, rot


#: Condition number of ∂(pose)/∂q′ above which a configuration is called near-singular.
SINGULAR_CONDITION = 1e4


def rotation_angle(vee, r_target, r) -> float:
    """Angle θ (rad, 0 to π) of ``R_targetᵀ R`` from its vector part ``vee`` (sin θ · axis)
    and its trace (1 + 2 cos θ): the vector part alone is 0 at θ = π as at θ = 0."""
    cos = (np.trace(np.asarray(r_target).T @ np.asarray(r)) - 1.0) / 2.0
    return float(np.arctan2(np.linalg.norm(np.asarray(vee)), cos))


def _reason(status: str, pos: float, rot: float, at_limit: list, condition: float) -> str:
    words = []
    if status not in _SOLVED:
        words.append(f"IPOPT: {status}")
    if pos > POSITION_TOLERANCE or rot > ROTATION_TOLERANCE:
        words.append(f"target not reached: off by {pos * 1000:.4g} mm, {np.degrees(rot):.3g} deg")
    if words and at_limit:
        words.append(f"at the limit of {', '.join(at_limit)}")
    if words and condition > SINGULAR_CONDITION:
        words.append(f"near a singularity or the edge of the workspace (condition number of "
                     f"the pose Jacobian {condition:.2g})")
    return "; ".join(words)


def _warn_unseen_orientation(tool, tcp_marker, position_only: bool) -> None:
    """Warn when the compensation relies on a flange orientation the markers did not see."""
    blind = blind_motion_words(tool)
    if blind and (tcp_marker is None or not position_only):
        what = "the orientation" if tcp_marker is not None else "a point that is not a marker"
        warnings.warn(f"compensating {what} from a calibration in which {blind.split(':')[0]}: "
                      f"that part follows the nominal flange rotation (use --position-only "
                      f"and --tcp MARKER for what was measured)", IdentifiabilityWarning,
                      stacklevel=3)


def compensate(model, result, targets, tcp, problem: CompensationProblem | None = None,
               position_only: bool = False, max_shift: float = MAX_SHIFT,
               tolerance: dict | None = None) -> CompensationResult:
    """Joint values that make the identified model reach each target.

    Parameters
    ----------
    model : Model
        Built from the result: ``build_model(result.robot, result.tool, result.model)``.
    result : IdentificationResult
    targets : Targets
    tcp : str or array_like, shape (3,)
        A marker name of the result, or a point in the flange frame (m).
    problem : CompensationProblem, optional
        :func:`~.nlp.build_problem` (built here, ``position_only``, when not given).
    max_shift : float
        Largest joint move (deg; mm for a prismatic joint) of a row not flagged.
    tolerance : dict, optional
        Stated prior std (SI) of the parameters the readings cannot separate
        (:func:`~doe_calib.estimation.unseen.tolerances`); one not given is its typical
        deviation (1 mm, 1 mrad), and the words say so.

    Returns
    -------
    CompensationResult
        A row not reached keeps its best q′, ``converged`` False and the reason
        (ConvergenceWarning); a dominating unseen part is an IdentifiabilityWarning, and so
        is, after a fit to socket contacts alone, what ``predicted_std`` is relative to
        (the sockets' frame; the scale's stated tolerance per metre: not in it); rows
        moved beyond ``max_shift`` or outside the measured joint range are flagged
        (DataWarning).

    Examples
    --------
    >>> targets = read_targets("program.csv", model.robot)  # doctest: +SKIP
    >>> print(compensate(model, result, targets, "A").summary())  # doctest: +SKIP
    """
    problem = build_problem(model, position_only) if problem is None else problem
    cfg = targets.configurations
    point, name = tcp_point(result.parameters, tcp)
    _warn_unseen_orientation(model.tool, name, problem.position_only)
    x_nom, r_nom = nominal_targets(model, result.parameters, cfg, point)
    x_t = x_nom if targets.positions is None else np.asarray(targets.positions, float)
    rows = _solve_rows(problem, model, result.parameters.values, cfg, point, x_t, r_nom)
    ok = np.array([not n for n in rows["note"]], bool)
    if not ok.all():
        bad = [f"{cfg.pose[i]} ({rows['note'][i]})" for i in np.flatnonzero(~ok)]
        warnings.warn(f"{len(bad)} target(s) not reached: {'; '.join(bad)}", ConvergenceWarning,
                      stacklevel=2)
    shifts = row_shift_flags(model.robot, cfg.q, rows["q"], max_shift, rows["distance"],
                             rows["angle"], rows["condition"])
    outside = outside_flags(model.robot, rows["q"], result.joint_range)
    for kind, words in (("with a large joint move", shifts), ("outside the measured region",
                                                               outside)):
        flagged = [f"{cfg.pose[i]} ({words[i]})" for i in range(len(cfg)) if words[i] and ok[i]]
        if flagged:
            warnings.warn(f"{len(flagged)} row(s) reached {kind}: {'; '.join(flagged)}",
                          DataWarning, stacklevel=2)
    flags = tuple("; ".join(w for w in pair if w) for pair in zip(shifts, outside))
    measured = measured_markers(result)
    part = (frame_unseen_part if from_contacts(result) else unseen_part)(
        model, result.parameters, measured, tolerance, within=result.joint_range)
    frame = targets.frame if targets.positions is not None else TRACKER
    placed = targets.placement_std   # robot-frame targets placed by measured base points
    compensated = type(cfg).from_arrays(rows["q"], cfg.wrench, cfg.env, cfg.pose)
    acc = row_accuracy(model, result, compensated, point, part, name,
                       frame if placed is None else TRACKER,
                       None if name else measured or list(model.tool.names))
    frame_said = frame_words(result.parameters, tolerance)
    words = "; ".join(w for w in (frame_said and f"predicted_std is {frame_said}",
                                  unseen_warning(acc, part, result.parameters, frame, name,
                                                 measured)) if w)
    if words:
        warnings.warn(words, IdentifiabilityWarning, stacklevel=2)
    std = acc.total if placed is None else np.hypot(acc.total, placed)
    return CompensationResult(
        robot=model.robot, model=result.model, tcp=point, tcp_marker=name,
        position_only=problem.position_only, pose=cfg.pose, q=cfg.q, q_compensated=rows["q"],
        wrench=cfg.wrench, target=x_t, residual=rows["position"],
        rotation_residual=rows["rotation"], predicted_std=std, converged=ok,
        note=tuple(rows["note"]), unseen_std=acc.unseen, frame=frame, flag=flags,
        unseen=words or "", tolerances=part.stated(result.parameters) if len(part) else "")


def _solve_rows(problem, model, values, cfg, point, x_t, r_nom) -> dict:
    """Solve each row: q′ (M, N), its errors (m, rad), note, and what the flags need."""
    robot = model.robot
    lower, upper = robot.lower, robot.upper
    m = len(cfg)
    out = {"q": np.empty_like(cfg.q), "note": [], **{k: np.empty(m) for k in (
        "position", "rotation", "distance", "angle", "condition")}}
    for i in range(m):
        args = (cfg.wrench[i], cfg.env[i], values, point)
        p = problem.nlp_parameters(x_t[i], r_nom[i], *args, cfg.q[i])
        sol = problem.solver(x0=np.clip(cfg.q[i], lower, upper), p=p, lbx=lower, ubx=upper,
                             lbg=0.0, ubg=0.0)
        status = problem.solver.stats()["return_status"]
        # IPOPT relaxes the bounds by ~1e-8: the program must stay inside them
        q = out["q"][i] = np.clip(np.asarray(sol["x"]).ravel(), lower, upper)
        for key, turn, at in (("position", "rotation", q), ("distance", "angle", cfg.q[i])):
            e_pos, e_rot = problem.error(at, *args, x_t[i], r_nom[i])
            out[key][i] = float(np.linalg.norm(np.asarray(e_pos)))
            out[turn][i] = 0.0 if problem.position_only else rotation_angle(
                e_rot, r_nom[i], model.flange(at, *args[:3])[0])
        at_limit = [j.name for j, v in zip(robot.joints, q)
                    if min(v - j.lower, j.upper - v) < 1e-9]
        jac = np.asarray(problem.jacobian(q, *args, x_t[i], r_nom[i]))
        out["condition"][i] = np.linalg.cond(jac)
        out["note"].append(_reason(status, out["position"][i], out["rotation"][i], at_limit,
                                   out["condition"][i]))
        log.debug("row %s: %s, %.3g mm", cfg.pose[i], status, out["position"][i] * 1000)
    return out
