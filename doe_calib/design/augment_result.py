"""The result of ``doe-calib design --augment``: the new poses and what they add."""
from __future__ import annotations

import textwrap
from dataclasses import asdict, dataclass, field

import numpy as np

from doe_calib.design.detectability import Detectability
from doe_calib.design.notes import reachability_words
from doe_calib.design.result import CandidateCount
from doe_calib.io.json_file import read_json, write_json
from doe_calib.io.measurements import Configurations
from doe_calib.model.robot import Robot
from doe_calib.model.tool import Tool

FORMAT = "doe_calib.augment"


def parameter_std(params, m: np.ndarray) -> dict:
    """Predicted std of each free parameter from scaled information ``m``: name →
    (std, unit) in display units; ``inf`` for a parameter the information cannot separate."""
    w, v = np.linalg.eigh(m)
    null = w <= 1e-13 * max(w.max(initial=0.0), 1e-300)
    var = (v[:, ~null] ** 2 / w[~null]).sum(axis=1)
    var[(v[:, null] ** 2).sum(axis=1) > 1e-6] = np.inf
    free = [p for p, f in zip(params.parameters, params.free) if f]
    return {p.name: (float(np.sqrt(s) * p.scale * p.display_factor), p.display_unit)
            for p, s in zip(free, var)}


@dataclass(frozen=True)
class Reached:
    """The new poses kept reachable: the ``home`` pose (deg, mm), the chosen poses
    ``replaced`` (reason → count) because no free path joins them to home or a tracker beam
    is blocked, and, when the home pose asked for was too close, that pose ``moved_from``
    (deg, mm) and the pair ``too_close``; ``note``: the words of a file written before."""

    home: list
    replaced: dict
    moved_from: list | None = None
    too_close: str = ""
    note: str = ""

    def words(self) -> str:
        return self.note or reachability_words(asdict(self))


@dataclass(frozen=True, eq=False)
class AugmentResult:
    """K new poses for a measured campaign, with the precision before and after.

    Attributes
    ----------
    configurations : Configurations
        The new poses, each unloaded then under every load case (or the one it
        picked, with load directions); pose ids from the candidate file, or ``new1``
        … ``newK``; the approach side of each joint (0 where not chosen).
    criterion : str
        ``D``, ``A``, ``E`` (the model's parameters) or ``Ds`` (the targets'
        information with the model's parameters projected out).
    targets : tuple of str
        Effect strings designed to be separated (empty: the model itself).
    value_before, value_after : float
        The criterion of the measured campaign and of campaign + new poses.
    std_before, std_after : dict
        Parameter name → (predicted std, display unit); the targets' parameters
        too when there are targets. ``inf`` where not separable.
    detect_before, detect_after : tuple of Detectability
        Of the targets (or the effects asked for) in the campaign, and with the new poses.
    candidates : CandidateCount
        How many candidates were drawn or read, kept and removed by which constraint.
    measured_configurations : int
    sigma_mm : float
        σ of the new readings, mm.
    robot : Robot
    model : str
    reachability : Reached or None
        None without a collision model.
    tool : Tool or None
    constraints : dict
        As a design's (its loads, cell file and collision model), for the program's check.
    """

    configurations: Configurations
    criterion: str
    targets: tuple
    value_before: float
    value_after: float
    std_before: dict
    std_after: dict
    detect_before: tuple
    detect_after: tuple
    candidates: CandidateCount
    measured_configurations: int
    sigma_mm: float
    robot: Robot
    model: str
    reachability: Reached | None = None
    tool: Tool | None = None
    constraints: dict = field(default_factory=dict)

    def summary(self) -> str:
        k = len(dict.fromkeys(self.configurations.pose))
        aim = ("separate " + ", ".join(self.targets) + " from the model"
               if self.targets else f"{self.criterion} criterion of {self.model}")
        lines = [f"{k} new poses for a campaign of {self.measured_configurations} "
                 f"configurations ({aim})",
                 f"  criterion {self.criterion}: {self.value_before:.4g} → "
                 f"{self.value_after:.4g}",
                 f"  candidates: {self.candidates.kept} kept of {self.candidates.drawn}"
                 + (f" from {self.candidates.source}" if self.candidates.source else ""),
                 "  poses: " + ", ".join(dict.fromkeys(self.configurations.pose)),
                 *([f"  {self.reachability.words()}"] if self.reachability else []),
                 "", "Predicted std (before → after)"]
        for name, (after, unit) in self.std_after.items():
            lines.append(f"  {name:<28} {self.std_before[name][0]:>10.4g} → {after:<10.4g} "
                         f"{unit}")
        if self.detect_after:
            lines += ["", "Detectability (before → after)"]
            for b, a in zip(self.detect_before, self.detect_after):
                lines += textwrap.wrap(f"before: {b}", 96, initial_indent="  ",
                                       subsequent_indent="    ")
                lines += textwrap.wrap(f"after:  {a}", 96, initial_indent="  ",
                                       subsequent_indent="    ")
        return "\n".join(lines)

    def __str__(self) -> str:
        return self.summary()

    def to_dict(self) -> dict:
        cfg, f = self.configurations, self.robot.display_factors
        return {"format": FORMAT, "model": self.model, "criterion": self.criterion,
                "targets": list(self.targets), "value_before": self.value_before,
                "value_after": self.value_after,
                "std_before": {n: [_num(s), u] for n, (s, u) in self.std_before.items()},
                "std_after": {n: [_num(s), u] for n, (s, u) in self.std_after.items()},
                "detectability_before": [d.to_dict() for d in self.detect_before],
                "detectability_after": [d.to_dict() for d in self.detect_after],
                "candidates": self.candidates.to_dict(),
                "measured_configurations": self.measured_configurations,
                "sigma_mm": self.sigma_mm, "robot": self.robot.to_dict(),
                "reachability": {} if self.reachability is None else
                {**asdict(self.reachability), "note": self.reachability.words()},
                "tool": None if self.tool is None else self.tool.to_dict(),
                "constraints": self.constraints,
                "configurations": [{"pose": p, "q": list(q * f), "wrench": list(w),
                                    "approach": [int(s) for s in a]}
                                   for p, q, w, a in zip(cfg.pose, cfg.q, cfg.wrench,
                                                         cfg.approach)]}

    def to_json(self, path=None) -> str:
        return write_json(self.to_dict(), path)

    @classmethod
    def from_dict(cls, d: dict) -> "AugmentResult":
        robot = Robot.from_dict(d["robot"])
        rows = d["configurations"]
        cfg = Configurations.from_arrays(
            np.array([r["q"] for r in rows], float).reshape(len(rows), robot.n_joints)
            / robot.display_factors, [r["wrench"] for r in rows], pose=[r["pose"] for r in rows],
            approach=np.array([r.get("approach", [0] * robot.n_joints) for r in rows],
                              float).reshape(len(rows), robot.n_joints))
        std = {k: {n: (np.inf if s is None else float(s), u) for n, (s, u) in d[k].items()}
               for k in ("std_before", "std_after")}
        return cls(configurations=cfg, criterion=d["criterion"], targets=tuple(d["targets"]),
                   value_before=float(d["value_before"]), value_after=float(d["value_after"]),
                   std_before=std["std_before"], std_after=std["std_after"],
                   detect_before=tuple(Detectability.from_dict(r)
                                       for r in d["detectability_before"]),
                   detect_after=tuple(Detectability.from_dict(r)
                                      for r in d["detectability_after"]),
                   candidates=CandidateCount(**d["candidates"]),
                   measured_configurations=int(d["measured_configurations"]),
                   sigma_mm=float(d["sigma_mm"]), robot=robot, model=d["model"],
                   reachability=Reached(**{**r, "note": "" if "too_close" in r else r["note"]})
                   if (r := d.get("reachability")) else None,  # a note as written: older files
                   tool=Tool.from_dict(d["tool"]) if d.get("tool") else None,
                   constraints=d.get("constraints", {}))

    @classmethod
    def from_json(cls, path) -> "AugmentResult":
        return cls.from_dict(read_json(path, FORMAT, "doe_calib augment"))


def _num(x: float):
    return float(x) if np.isfinite(x) else None
