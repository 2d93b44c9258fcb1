"""An ISO 9283 pose test's outcome: per pose AP and RP, the distance pair, per campaign.

A campaign is one measured run of the test (before compensation, after it); the result
holds them side by side. Lengths in mm, angles in degrees, as the standard reports them.
"""
from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from doe_calib.io.json_file import read_json, write_json
from doe_calib.iso9283.standard import (
    DISTANCE_PAIR,
    distance_characteristics,
    orientation_characteristics,
    position_characteristics,
)

FORMAT = "doe_calib.iso9283"
#: Orientation keys of a pose, in the order :attr:`PoseResult.orientation_deg` holds them.
ORIENTATION_KEYS = ("AP_a_deg", "AP_b_deg", "AP_c_deg", "RP_a_deg", "RP_b_deg", "RP_c_deg")


@dataclass(frozen=True)
class PoseResult:
    """ISO 9283 pose accuracy and repeatability of one pose in one campaign.

    Attributes
    ----------
    pose : str
        ``P1`` … ``P5``.
    n : int
        Cycles measured.
    ap_mm, apx_mm, apy_mm, apz_mm : float
        Position accuracy AP and its components x̄ − x_c, ȳ − y_c, z̄ − z_c, mm.
    rp_mm : float
        Position repeatability RP = l̄ + 3 S_l, mm.
    commanded_mm, mean_mm : tuple of float
        The commanded position and the mean attained one (x̄, ȳ, z̄), robot base frame, mm.
    orientation_deg : tuple of float
        AP_a, AP_b, AP_c, RP_a, RP_b, RP_c in degrees (:data:`ORIENTATION_KEYS`); empty
        when the readings give no orientation.
    """

    pose: str
    n: int
    ap_mm: float
    apx_mm: float
    apy_mm: float
    apz_mm: float
    rp_mm: float
    commanded_mm: tuple
    mean_mm: tuple
    orientation_deg: tuple = ()

    def to_dict(self) -> dict:
        out = {"AP_mm": self.ap_mm, "APx_mm": self.apx_mm, "APy_mm": self.apy_mm,
               "APz_mm": self.apz_mm, "RP_mm": self.rp_mm, "n": self.n,
               "commanded_mm": list(self.commanded_mm), "mean_mm": list(self.mean_mm)}
        return {**out, **dict(zip(ORIENTATION_KEYS, self.orientation_deg))}

    @classmethod
    def from_dict(cls, pose: str, d: dict) -> "PoseResult":
        return cls(pose, int(d["n"]), float(d["AP_mm"]), float(d["APx_mm"]),
                   float(d["APy_mm"]), float(d["APz_mm"]), float(d["RP_mm"]),
                   tuple(d["commanded_mm"]), tuple(d["mean_mm"]),
                   tuple(float(d[k]) for k in ORIENTATION_KEYS if k in d))


@dataclass(frozen=True)
class DistanceResult:
    """ISO 9283 distance accuracy AD = |D̄ − D_c| and repeatability RD = ±3 S_D (mm) between
    ``poses`` over ``n`` cycles; ``mean_mm`` D̄, ``commanded_mm`` D_c."""

    poses: tuple
    n: int
    ad_mm: float
    rd_mm: float
    mean_mm: float
    commanded_mm: float

    def to_dict(self) -> dict:
        return {"poses": list(self.poses), "n": self.n, "AD_mm": self.ad_mm,
                "RD_mm": self.rd_mm, "D_mean_mm": self.mean_mm, "Dc_mm": self.commanded_mm}

    @classmethod
    def from_dict(cls, d: dict) -> "DistanceResult":
        return cls(tuple(d["poses"]), int(d["n"]), float(d["AD_mm"]), float(d["RD_mm"]),
                   float(d["D_mean_mm"]), float(d["Dc_mm"]))


@dataclass(frozen=True)
class Campaign:
    """One measured run of the test: its ``name`` (the session), each pose's result in the
    standard's order, and the distance pair's (None when a pose of the pair is missing)."""

    name: str
    poses: tuple
    distance: DistanceResult | None = None

    def __getitem__(self, pose: str) -> PoseResult:
        return next(p for p in self.poses if p.pose == pose)

    @classmethod
    def from_cycles(cls, name: str, positions: dict, commanded: dict, cycles: dict | None = None,
                    rotations: dict | None = None,
                    commanded_rotations: dict | None = None) -> "Campaign":
        """The characteristics of attained positions (and orientations) against commanded ones.

        Parameters
        ----------
        name : str
        positions : dict
            Pose → attained positions (n, 3), mm, robot base frame, one row per cycle.
        commanded : dict
            Pose → commanded position (3,), mm.
        cycles : dict, optional
            Pose → the cycle number of each row (n,), which pairs the distance pair's rows;
            default 1 … n.
        rotations, commanded_rotations : dict, optional
            Pose → attained orientations (n, 3, 3) and the commanded one (3, 3), base frame.

        Examples
        --------
        >>> x = {"P1": [[0.0, 0.0, 1.0], [0.0, 0.0, 3.0]]}
        >>> Campaign.from_cycles("run", x, {"P1": [0.0, 0.0, 0.0]})["P1"].ap_mm
        2.0
        """
        cycles = cycles or {p: np.arange(1, len(x) + 1) for p, x in positions.items()}
        out = []
        for pose, x in positions.items():
            pc = position_characteristics(x, commanded[pose])
            orientation = ()
            if rotations is not None and pose in rotations:
                oc = orientation_characteristics(rotations[pose], commanded_rotations[pose])
                orientation = tuple(float(np.degrees(oc[k[:4]])) for k in ORIENTATION_KEYS)
            out.append(PoseResult(pose, len(np.asarray(x)), pc["AP"], pc["APx"], pc["APy"],
                                  pc["APz"], pc["RP"], tuple(map(float, commanded[pose])),
                                  tuple(map(float, pc["mean"])), orientation))
        return cls(name, tuple(out), _distance(positions, commanded, cycles))

    def to_dict(self) -> dict:
        return {"name": self.name, "poses": {p.pose: p.to_dict() for p in self.poses},
                "distance": None if self.distance is None else self.distance.to_dict()}

    @classmethod
    def from_dict(cls, d: dict) -> "Campaign":
        return cls(d["name"], tuple(PoseResult.from_dict(p, v) for p, v in d["poses"].items()),
                   None if d.get("distance") is None else DistanceResult.from_dict(d["distance"]))


def _distance(positions: dict, commanded: dict, cycles: dict) -> DistanceResult | None:
    """AD and RD over the cycles in which both poses of :data:`DISTANCE_PAIR` were measured."""
    first, second = DISTANCE_PAIR
    if first not in positions or second not in positions:
        return None
    index = [{int(c): row for row, c in enumerate(cycles[p])} for p in DISTANCE_PAIR]
    both = sorted(set(index[0]) & set(index[1]))
    if len(both) < 2:
        return None
    x = [np.asarray(positions[p], float)[[ix[c] for c in both]]
         for p, ix in zip(DISTANCE_PAIR, index)]
    d = distance_characteristics(x[0], x[1], commanded[first], commanded[second])
    return DistanceResult(DISTANCE_PAIR, d["n"], d["AD"], d["RD"], d["D_mean"], d["D_c"])


@dataclass(frozen=True, eq=False)
class Iso9283Result:
    """An ISO 9283 pose test: each measured campaign's characteristics, side by side.

    Attributes
    ----------
    campaigns : tuple of Campaign
        In the order measured (before compensation, then after).
    tcp : str
        The marker whose readings are the attained positions.
    frame : str
        How the readings were taken into the robot base frame, in words.
    notes : tuple of str
    predicted : dict
        Pose → ``{"AP_mm", "std_mm", "RP_noise_mm"}`` the test's design predicted after
        compensation (:mod:`~doe_calib.iso9283.predicted`); empty when it has none.

    Examples
    --------
    >>> r = Iso9283Result.from_json("iso_report.json")  # doctest: +SKIP
    >>> r.poses["P1"].rp_mm  # doctest: +SKIP
    0.061
    """

    campaigns: tuple
    tcp: str
    frame: str
    notes: tuple = ()
    predicted: dict = field(default_factory=dict)

    @property
    def poses(self) -> dict:
        """Pose → :class:`PoseResult` of the last campaign (the robot as it now is)."""
        return {p.pose: p for p in self.campaigns[-1].poses}

    def summary(self) -> str:
        lines = [f"ISO 9283 pose accuracy and repeatability, TCP {self.tcp} ({self.frame})"]
        for c in self.campaigns:
            lines += ["", f"campaign {c.name}:",
                      f"{'pose':<6}{'n':>4}{'AP':>11}{'APx':>11}{'APy':>11}{'APz':>11}"
                      f"{'RP':>11}  mm"]
            lines += [f"{p.pose:<6}{p.n:>4}{p.ap_mm:11.4f}{p.apx_mm:11.4f}{p.apy_mm:11.4f}"
                      f"{p.apz_mm:11.4f}{p.rp_mm:11.4f}" for p in c.poses]
            if any(p.orientation_deg for p in c.poses):
                lines.append(f"{'pose':<10}" + "".join(f"{k[:4]:>11}" for k in ORIENTATION_KEYS)
                             + "  deg")
                lines += [f"{p.pose:<10}" + "".join(f"{v:11.4f}" for v in p.orientation_deg)
                          for p in c.poses if p.orientation_deg]
            d = c.distance
            if d is not None:
                lines.append(f"distance {d.poses[0]}–{d.poses[1]} ({d.n} cycles): AD "
                             f"{d.ad_mm:.4f} mm, RD ±{d.rd_mm:.4f} mm (D̄ {d.mean_mm:.4f}, "
                             f"D_c {d.commanded_mm:.4f} mm)")
        if self.predicted:
            lines += ["", "predicted after compensation (the design's; AP as an RMS, RP of the "
                          "readings' noise alone):"]
            lines += [f"{pose:<10}{p['AP_mm']:11.4f}{'':33}{p['RP_noise_mm']:11.4f}"
                      for pose, p in self.predicted.items()]
        return "\n".join(lines + [f"note: {n}" for n in self.notes])

    def __str__(self) -> str:
        return self.summary()

    def to_dict(self) -> dict:
        return {"format": FORMAT, "tcp": self.tcp, "frame": self.frame,
                "poses": {p: v.to_dict() for p, v in self.poses.items()},
                "campaigns": [c.to_dict() for c in self.campaigns], "notes": list(self.notes),
                **({"predicted": self.predicted} if self.predicted else {})}

    def to_json(self, path=None) -> str:
        """JSON text; also written to ``path`` when given."""
        return write_json(self.to_dict(), path)

    @classmethod
    def from_dict(cls, d: dict) -> "Iso9283Result":
        """The result of :meth:`to_dict` (its ``poses`` are the last campaign's, re-derived)."""
        return cls(tuple(Campaign.from_dict(c) for c in d["campaigns"]), d["tcp"], d["frame"],
                   tuple(d.get("notes", ())), dict(d.get("predicted", {})))

    @classmethod
    def from_json(cls, path) -> "Iso9283Result":
        return cls.from_dict(read_json(path, FORMAT, "doe_calib ISO 9283 report"))
