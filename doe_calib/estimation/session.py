"""A new session: re-fit the tracker frame (and the tool mounting) on new readings.

Every validation session starts with a tracker that has moved since the
calibration, and often a probe that was taken off and put back. The robot
parameters of an identification result still hold; what changed is the rigid
pose of the robot base in the tracker frame (6 parameters) and, after a
remount, the marker positions on the flange. :func:`reregister` re-fits those
with the point estimator's Levenberg–Marquardt step
(:func:`~doe_calib.estimation.point_fit.point_fit`), every robot parameter
held at the result's value (:meth:`ParameterSet.fixed`).
"""
from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from doe_calib.errors import OptionError
from doe_calib.estimation.point_fit import point_fit
from doe_calib.estimation.preparation import register_base
from doe_calib.estimation.weighted_residuals import marker_residuals
from doe_calib.model.rotations import rotation_vector_to_matrix

#: What may be re-fitted: the parameter blocks each choice frees.
REGISTER_BLOCKS = {"frame": ("base",), "frame+tool": ("base", "markers")}
#: Why the other parameters are held, in the result's fixed list.
HELD = "held at the calibration's value while re-registering a new session"


def error_mm(residuals) -> dict:
    """RMS per coordinate, 3-D RMS, mean and max 3-D error of residuals (K, 3) in m, in mm."""
    e = np.asarray(residuals, float) * 1000.0
    d = np.linalg.norm(e, axis=1)
    return {"rms_mm": float(np.sqrt(np.mean(e ** 2))),
            "rms_3d_mm": float(np.sqrt(np.mean(d ** 2))), "mean_3d_mm": float(d.mean()),
            "max_3d_mm": float(d.max())}


@dataclass(frozen=True, eq=False)
class Reregistration:
    """What re-registering a new session changed, and the error before and after.

    Attributes
    ----------
    what : str
        ``"frame"`` (the 6 base parameters) or ``"frame+tool"`` (also the
        marker positions on the flange).
    parameters : ParameterSet
        The result's parameters with the re-fitted ones replaced (SI); the
        re-fitted ones free, every other one fixed.
    frame_shift_mm : ndarray, shape (3,)
        Change of the base position in the tracker frame, mm.
    frame_rotation_deg : float
        Angle of the rotation between the old and the new base orientation, deg.
    marker_shifts_mm : dict
        Marker name → distance it moved on the flange, mm (``frame+tool`` only).
    before, after : dict
        Error of the readings with the calibration's and the re-fitted
        parameters: ``rms_mm`` (per coordinate), ``rms_3d_mm``, ``mean_3d_mm``,
        ``max_3d_mm``.
    converged : bool
    notes : tuple of str
    """

    what: str
    parameters: object
    frame_shift_mm: np.ndarray
    frame_rotation_deg: float
    marker_shifts_mm: dict
    before: dict
    after: dict
    converged: bool = True
    notes: tuple = field(default=())

    @property
    def removed(self) -> float:
        """Fraction of the 3-D RMS error the re-registration removed (0 to 1)."""
        b = self.before["rms_3d_mm"]
        return 0.0 if b == 0 else 1.0 - self.after["rms_3d_mm"] / b

    def summary(self) -> str:
        """A few lines: what was re-fitted, by how much, and the error before and after."""
        s = self.frame_shift_mm
        lines = [f"re-registered {self.what}: tracker frame moved "
                 f"{np.linalg.norm(s):.3f} mm ({s[0]:.3f}, {s[1]:.3f}, {s[2]:.3f}) and turned "
                 f"{self.frame_rotation_deg:.4f} deg"]
        if self.marker_shifts_mm:
            lines.append("markers moved on the flange: " + ", ".join(
                f"{n} {d:.3f} mm" for n, d in self.marker_shifts_mm.items()))
        lines.append(f"3-D RMS error {self.before['rms_3d_mm']:.4f} mm before, "
                     f"{self.after['rms_3d_mm']:.4f} mm after "
                     f"(max {self.after['max_3d_mm']:.4f} mm)")
        if not self.converged:
            lines.append("the re-registration stopped before converging")
        return "\n".join(lines + list(self.notes))

    def __str__(self) -> str:
        return self.summary()

    def to_dict(self) -> dict:
        """JSON-able dict (display units: mm, deg); the re-fitted values by name."""
        k = self.parameters
        idx = k.index(list(REGISTER_BLOCKS[self.what]))
        return {"what": self.what,
                "frame_shift_mm": [float(v) for v in self.frame_shift_mm],
                "frame_rotation_deg": self.frame_rotation_deg,
                "marker_shifts_mm": dict(self.marker_shifts_mm),
                "refitted": {k.names[i]: float(k.values[i] * k.parameters[i].display_factor)
                             for i in idx},
                "before": dict(self.before), "after": dict(self.after),
                "converged": self.converged, "notes": list(self.notes)}


def reregister(model, params, measurements, what: str = "frame",
               max_iterations: int = 100) -> Reregistration:
    """Re-fit the tracker frame (and the tool mounting) to new readings, robot held.

    Parameters
    ----------
    model : Model
        The model the parameters belong to.
    params : ParameterSet
        The calibration's parameters (SI), e.g. ``result.parameters``.
    measurements : Measurements
        The new session's readings (with x, y, z).
    what : {"frame", "frame+tool"}
        ``frame``: the 6 base parameters (the tracker moved); ``frame+tool``:
        also the marker positions on the flange (the probe was remounted).
    max_iterations : int
        Jacobian evaluations allowed.

    Returns
    -------
    Reregistration

    Raises
    ------
    OptionError
        ``what`` is not one of :data:`REGISTER_BLOCKS`.
    """
    if what not in REGISTER_BLOCKS:
        raise OptionError(f"register {what!r}: expected one of {', '.join(REGISTER_BLOCKS)}")
    blocks = list(REGISTER_BLOCKS[what])
    start = params.fixed(params.names, HELD).freed(blocks)
    before = error_mm(marker_residuals(model, measurements, params.values))
    start = register_base(model, measurements, start)
    sol = point_fit(model, measurements, start, max_iterations)
    new = start.with_free_values(sol.x)
    after = error_mm(marker_residuals(model, measurements, new.values))
    base = params.index("base")
    old_v, new_v = params.values[base], new.values[base]
    turn = rotation_vector_to_matrix(new_v[3:]) @ rotation_vector_to_matrix(old_v[3:]).T
    angle = float(np.degrees(np.arccos(np.clip((np.trace(turn) - 1) / 2, -1.0, 1.0))))
    moved = {n: params.index([f"marker_{n}_{c}" for c in "xyz"]) for n in model.tool.names}
    shifts = {n: float(np.linalg.norm(new.values[i] - params.values[i]) * 1000.0)
              for n, i in moved.items()} if "markers" in blocks else {}
    notes = () if sol.converged else (f"Levenberg–Marquardt: {sol.message}",)
    return Reregistration(what, new, (new_v[:3] - old_v[:3]) * 1000.0, angle, shifts, before,
                          after, sol.converged, notes)


#: An error this many times the expected one (σ̂ and the prediction's std) is "far beyond".
FAR = 5.0
#: A re-registration that leaves less than this fraction of the error "removes most of it".
MOST = 0.5


def session_notes(model, params, measurements, expected_m: float,
                  done: Reregistration | None = None) -> tuple:
    """Words for an error far beyond the prediction that a re-registration would remove.

    Parameters
    ----------
    model : Model
    params : ParameterSet
        The parameters the readings were predicted with (after ``done``, if any).
    measurements : Measurements
        The readings, with x, y, z.
    expected_m : float
        The error per coordinate the prediction expects, m: √(σ̂² + mean std²).
    done : Reregistration, optional
        The re-registration already made (``frame`` or ``frame+tool``).

    Returns
    -------
    tuple of str
        Empty when the error is within :data:`FAR` times ``expected_m``;
        otherwise what a (further) re-registration removes, naming the option.
    """
    rms = error_mm(marker_residuals(model, measurements, params.values))["rms_mm"] / 1000.0
    if not rms > FAR * expected_m:
        return ()
    far = (f"the error ({rms * 1000:.4g} mm RMS per coordinate) is {rms / expected_m:.3g} times "
           f"what the prediction expects ({expected_m * 1000:.3g} mm: σ̂ and the parameters' "
           f"std)")
    if done is None:
        frame = reregister(model, params, measurements, "frame")
        if frame.after["rms_mm"] / 1000.0 > FAR * expected_m:
            tool = reregister(model, params, measurements, "frame+tool")
            if tool.after["rms_3d_mm"] < MOST * frame.after["rms_3d_mm"]:
                return (f"{far}; re-fitting the tracker frame and the tool mounting removes most "
                        f"of it ({tool.before['rms_3d_mm']:.4g} → {tool.after['rms_3d_mm']:.4g} "
                        "mm 3-D RMS): the tracker moved and the probe was remounted since the "
                        "calibration; predict with --register frame+tool "
                        "(register=\"frame+tool\" in Python)",)
        if frame.removed > 1 - MOST:
            return (f"{far}; re-fitting the tracker frame removes most of it "
                    f"({frame.before['rms_3d_mm']:.4g} → {frame.after['rms_3d_mm']:.4g} mm "
                    "3-D RMS): the tracker moved since the calibration; predict with "
                    "--register frame (register=\"frame\" in Python)",)
        return (f"{far}, and re-fitting the tracker frame does not remove it: the robot "
                "parameters do not hold for these readings (another robot, load or tool?)",)
    if done.what == "frame":
        tool = reregister(model, params, measurements, "frame+tool")
        if tool.removed > 1 - MOST:
            return (f"after re-fitting the tracker frame, {far}; re-fitting the tool mounting as "
                    f"well removes most of it ({tool.before['rms_3d_mm']:.4g} → "
                    f"{tool.after['rms_3d_mm']:.4g} mm 3-D RMS, markers moved "
                    + ", ".join(f"{n} {d:.3g} mm" for n, d in tool.marker_shifts_mm.items())
                    + "): the probe was likely remounted; predict with --register frame+tool",)
    return (f"after re-fitting the {done.what}, {far}: the robot parameters do not hold for "
            "these readings (another load, temperature or a change to the robot?)",)
