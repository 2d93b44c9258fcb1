"""How well a compensated TCP lands: what the fit's covariance says and what the readings never saw.

The predicted std of a row has two parts (both 3-D, 1σ, m):

* **seen**: ``√tr(J Σ Jᵀ)``, J the TCP's Jacobian wrt the free parameters and
  Σ the result's a-posteriori covariance;
* **unseen**: ``√tr(G diag(s²) Gᵀ)`` of the parameters the readings could not
  separate, at their tolerances s (the user's, else each one's typical deviation, said
  so; :mod:`doe_calib.estimation.unseen`): ~0 for a measured marker in the tracker
  frame, not for a TCP never measured or targets in a robot frame (the base pose does
  not split from the first joint).

A TCP given as a point is taken rigid with the measured markers (the tolerance of a
TCP known only on the mechanical flange is yours to add); targets in a robot frame use
the TCP in the robot base frame.
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from doe_calib.compensation.targets import TRACKER
from doe_calib.estimation.unseen import ASK, UnseenPart
from doe_calib.model.evaluation import evaluate
from doe_calib.model.rotations import skew_matrix


def point_jacobian(model, values, configurations, point, marker: str | None = None,
                   frame: str = TRACKER, carried_by=None) -> np.ndarray:
    """Jacobian (M, 3, P) of a flange point's position wrt every parameter, m per SI unit.

    Parameters
    ----------
    point : array_like, shape (3,)
        Flange frame, m.
    marker : str, optional
        The marker the point is: its ``marker_<name>_{x,y,z}`` columns get the
        flange rotation R (the point moves with them).
    frame : str
        ``tracker``: tracker frame (``model.point``); any other: the robot base frame
        (``model.point_robot``; a frame fixed to the base only turns it).
    carried_by : sequence of str, optional
        For a point that is no marker: the measured markers it is rigid with. Their
        columns get ``R L``, L (3, 3K) the move of the point under the rigid motion
        that best follows a change of their positions (least squares), so the point
        goes where the markers take the flange frame.
    """
    f = model.point if frame == TRACKER else model.point_robot
    point = np.asarray(point, float)
    x0, jac = evaluate(f, configurations, values, point)
    jac = np.array(jac)
    if marker is None and not carried_by:
        return jac
    # the point is affine in t: x(t + e_k) − x(t) = R e_k exactly
    rot = np.stack([evaluate(f, configurations, values, point + e)[0][:, :, 0] - x0[:, :, 0]
                    for e in np.eye(3)], axis=2)
    names = model.nominal().names
    if marker is not None:
        carried_by, follow = [marker], np.eye(3)
    else:
        where = np.array([[values[names.index(f"marker_{m}_{a}")] for a in "xyz"]
                          for m in carried_by])
        follow = _rigid_follow(where, point)
    for j, m in enumerate(carried_by):
        cols = [names.index(f"marker_{m}_{a}") for a in "xyz"]
        jac[:, :, cols] = rot @ follow[:, 3 * j:3 * j + 3]
    return jac


def _rigid_follow(markers, point) -> np.ndarray:
    """L (3, 3K): how ``point`` moves under the small rigid motion fitted to moves of ``markers``
    (K, 3), all m, flange frame (``δu_j ≈ v + ω × u_j``, least squares, ω scaled by the
    markers' size; minimum norm where they do not fix the rotation)."""
    size = max(float(np.ptp(markers, axis=0).max(initial=0.0)), 1e-3)
    rows = np.vstack([np.hstack([np.eye(3), -skew_matrix(u) / size]) for u in markers])
    return np.hstack([np.eye(3), -skew_matrix(point) / size]) @ np.linalg.pinv(rows, rcond=1e-9)


@dataclass(frozen=True)
class RowAccuracy:
    """Predicted std of each row's TCP and its parts, m, shape (M,) each.

    ``unseen_tracker`` is the unseen part in the tracker frame (what the robot-frame
    part is compared with to tell the base split as its cause).
    """

    total: np.ndarray
    seen: np.ndarray
    unseen: np.ndarray
    unseen_tracker: np.ndarray
    largest: tuple


def row_accuracy(model, result, configurations, point, part: UnseenPart,
                 marker: str | None = None, frame: str = TRACKER,
                 carried_by=None) -> RowAccuracy:
    """Seen and unseen std (m) of the TCP ``point`` (flange frame, m) at each compensated
    configuration (module notes); ``part``: the result's unseen parameters with their
    tolerances; ``marker``, ``frame``, ``carried_by`` as :func:`point_jacobian`."""
    values = result.parameters.values

    def jacobian(cfg, in_frame):
        return point_jacobian(model, values, cfg, point, marker, in_frame, carried_by)

    jac = jacobian(configurations, frame)
    j = jac[:, :, result.parameters.free]
    seen = np.sqrt(np.clip(np.einsum("mij,jk,mik->m", j, result.cov_params(), j), 0, None))
    bare = type(configurations).from_arrays(configurations.q, None, configurations.env)
    unloaded = jacobian(bare, frame)
    unseen = part.std_3d(jac, unloaded)
    in_tracker = unseen if frame == TRACKER else \
        part.std_3d(jacobian(configurations, TRACKER), jacobian(bare, TRACKER))
    return RowAccuracy(np.hypot(seen, unseen), seen, unseen, in_tracker,
                       tuple(part.largest(jac, unloaded)))


def unseen_warning(accuracy: RowAccuracy, part: UnseenPart, params, frame: str,
                   tcp_marker: str | None, measured) -> str | None:
    """Words for a warning when the unseen part dominates some row's std (cause, size in mm
    at 1σ, remedy), None otherwise."""
    worst = int(np.argmax(accuracy.unseen - accuracy.seen)) if len(accuracy.unseen) else 0
    if not len(accuracy.unseen) or accuracy.unseen[worst] <= accuracy.seen[worst]:
        return None
    causes, remedies = [], []
    if tcp_marker is not None and measured is not None and tcp_marker not in measured:
        causes.append(f"TCP {tcp_marker} was never measured (the readings hold "
                      f"{', '.join(measured)} only): its place on the flange is the tool "
                      f"file's")
        remedies.append(f"measure {tcp_marker}, with 3 markers not on one line")
    if frame != TRACKER and np.max(accuracy.unseen) > 2 * np.max(accuracy.unseen_tracker):
        causes.append(f"the targets are in the robot frame {frame!r}, and the readings cannot "
                      f"split the base pose from the first joints "
                      f"({', '.join(accuracy.largest)})")
        remedies.append("give the targets in the tracker frame, or measure points known on "
                        "the robot's base with the tracker (--base-points)")
    if not causes:
        causes.append(f"the readings cannot see {', '.join(accuracy.largest)}")
        remedies.append("measure poses that move these parameters")
    if part.defaulted:
        remedies.append(ASK)
    return (f"{'; and '.join(causes)}. At the tolerances of the parameters the readings "
            f"cannot separate ({part.stated(params)}), this moves the TCP by up to "
            f"{np.max(accuracy.unseen) * 1000:.3g} mm (1σ), against "
            f"{np.max(accuracy.seen) * 1000:.3g} mm from the fit; predicted_std includes it. "
            f"Remedy: {'; or '.join(remedies)}")
