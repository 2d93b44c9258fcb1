"""A design: chosen poses with their load cases, what they promise, and its JSON form."""
from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from doe_calib.design.detectability import Detectability
from doe_calib.design.predicted_std import PredictedStd, StdMapping, predicted_std
from doe_calib.errors import DataError
from doe_calib.io.json_file import read_json, write_json
from doe_calib.io.measurements import Configurations
from doe_calib.model.robot import Robot
from doe_calib.model.tool import Tool

FORMAT = "doe_calib.design"


@dataclass(frozen=True, eq=False)
class DesignResult:
    """N poses to measure, each under its load cases.

    Attributes
    ----------
    robot, tool : Robot, Tool
    model : str
        Effects the design is for.
    configurations : Configurations
        Every (pose, load case) to measure, poses in measuring order.
    criterion : str
        ``D``, ``A``, ``E`` or ``task``.
    value : float
        Criterion of the design (scaled parameters): log det M, −tr M⁻¹,
        λ_min(M) or −tr(T M⁻¹ Tᵀ) (m²).
    bound : float
        Certified upper bound of the criterion over designs of the same size
        from the candidates (and the refined poses).
    efficiency : float
        Efficiency against the bound in the criterion's own terms
        (:func:`.criteria.efficiency`; D: (det M / det M_bound)^(1/p)).
    predicted_std : dict
        Parameter name → (std in display units, unit).
    constraints : dict
        The constraints the poses satisfy, as used (file units) with the loads.
    notes : tuple of str
        Comparisons and remarks, in words.
    efficiencies : dict
        Criterion → efficiency against that criterion's certified bound
        (the design's criterion, and D).
    criteria : dict
        Criterion → value of the design (D, A, E, and task when given).
    equivalence : dict
        The equivalence-theorem check: the statistic, its target, its value
        at the relaxation (certifies the bound) and at the design.
    candidates : dict
        Poses drawn, kept, and removed by each constraint.
    refinement : dict
        The continuous refinement's outcome (empty when not run).
    coverage : dict
        Bins used by the poses and how many were asked for (empty when none).
    versus_random : dict
        ``designs`` (random designs of the same size drawn from the feasible
        candidates), ``singular_fraction`` (share of them that cannot identify
        every parameter) and ``equivalent_poses`` (how many random poses are as
        precise, D criterion, against their median; None when that median is
        singular).
    sigma_mm : float or None
        The tracker σ per coordinate (mm) the predicted std are for (None in
        design files written before it was stored).
    clearances : tuple of (float, str)
        Per pose, in measuring order: its clearance (mm) and the pair with
        least distance to spare (:mod:`doe_calib.collision`); empty when not
        checked.
    stages : dict
        Each solver's outcome (:meth:`.outcome.DesignOutcome.to_dict`) by stage:
        ``relaxation``, ``exchange`` and, when run, ``refinement`` (empty in
        design files written before it was stored).

    Examples
    --------
    >>> d = DesignResult.from_json("design.json")  # doctest: +SKIP
    >>> d.std["k_a3"], d["k_a3"].display_unit  # doctest: +SKIP
    (2.1e-07, 'µrad/(N·m)')
    """

    robot: Robot
    tool: Tool
    model: str
    configurations: Configurations
    criterion: str
    value: float
    bound: float
    efficiency: float
    predicted_std: dict
    constraints: dict
    notes: tuple = field(default=())
    efficiencies: dict = field(default_factory=dict)
    criteria: dict = field(default_factory=dict)
    equivalence: dict = field(default_factory=dict)
    candidates: dict = field(default_factory=dict)
    refinement: dict = field(default_factory=dict)
    coverage: dict = field(default_factory=dict)
    versus_random: dict = field(default_factory=dict)
    sigma_mm: float | None = None
    clearances: tuple = ()
    stages: dict = field(default_factory=dict)
    detectability: tuple = ()

    @property
    def std(self) -> StdMapping:
        """Parameter name → predicted std in SI units; ``.display()`` in display units."""
        return StdMapping((predicted_std(n, s, u) for n, (s, u) in self.predicted_std.items()),
                          self.robot.joint_names)

    def __getitem__(self, name: str) -> PredictedStd:
        """The predicted std of parameter ``name``: SI and display value, both units."""
        return self.std.record(name)

    def __repr__(self) -> str:
        return (f"<DesignResult: {len(self.poses())} poses, {self.criterion} criterion, "
                f"efficiency {self.efficiency:.3f}>")

    def __str__(self) -> str:
        return self.summary()

    def first_configurations(self) -> np.ndarray:
        """Index of each pose's first configuration (its unloaded one), in measuring order."""
        cfg = self.configurations
        return np.array(sorted({p: i for i, p in reversed(list(enumerate(cfg.pose)))}.values()),
                        int)

    def nominal_points(self) -> tuple[np.ndarray, np.ndarray]:
        """Flange and marker positions at each pose's first configuration, mm, robot base frame.

        The robot's nominal chain and the tool's nominal markers (no effect at
        all, as unloaded with every effect at zero): what a design file holds is
        enough, whatever effects its model names.

        Returns
        -------
        flange : ndarray, shape (M, 3)
        markers : ndarray, shape (M, n, 3)
        """
        rotation, translation = self.robot.flange_poses(self.configurations.q[
            self.first_configurations()])
        markers = translation[:, None, :] + np.einsum("mij,nj->mni", rotation,
                                                      np.asarray(self.tool.positions, float))
        return translation * 1000.0, markers * 1000.0

    def poses(self) -> list[dict]:
        """One entry per pose: id, q in deg (mm for prismatic joints), its wrenches, approach
        and, when checked, ``clearance_mm`` and ``clearance_pair``.

        ``approach`` is the planned direction of each joint (+1 reached moving
        up, −1 moving down, 0 no requirement), the same for every load case
        of the pose; load cases that plan different directions are refused.
        """
        out, index = [], {}
        cfg = self.configurations
        for c, pose in enumerate(cfg.pose):
            approach = [int(a) for a in cfg.approach[c]]
            if pose not in index:
                index[pose] = len(out)
                out.append({"pose": pose,
                            "q_deg": (cfg.q[c] * self.robot.display_factors).tolist(),
                            "wrenches": [], "approach": approach})
            entry = out[index[pose]]
            if entry["approach"] != approach:
                raise DataError(f"pose {pose!r}: its load cases plan different approach "
                                f"directions ({entry['approach']}, {approach}); a design plans "
                                f"one per pose")
            entry["wrenches"].append(cfg.wrench[c].tolist())
        for entry, (mm, pair) in zip(out, self.clearances):
            entry["clearance_mm"], entry["clearance_pair"] = float(mm), pair
        return out

    def summary(self) -> str:
        lines = [f"Design of {len(self.poses())} poses ({len(self.configurations)} measurements) "
                 f"for model {self.model}, criterion {self.criterion}",
                 f"criterion {self.value:.6g}, certified bound {self.bound:.6g}, "
                 f"{self.criterion}-efficiency {self.efficiency:.3f}"]
        if self.efficiencies:
            lines.append("efficiency against each certified bound: " + ", ".join(
                f"{k} {v:.3f}" for k, v in self.efficiencies.items()))
        if self.criteria:
            lines.append("criteria: " + ", ".join(f"{k} {v:.6g}" for k, v in self.criteria.items()))
        if self.equivalence:
            e = self.equivalence
            lines.append(f"equivalence theorem: {e['statistic']} = {e['relaxation']:.4g} at the "
                         f"relaxation, {e['design']:.4g} at the design (target {e['target']:g}; "
                         f"design efficiency against the approximate optimum ≥ "
                         f"{e['design_efficiency_at_least']:.3f})")
        if self.candidates:
            c = self.candidates
            lines.append(f"candidates: {c['kept']} kept of {c['drawn']} drawn" + "".join(
                f"; {k} removed {v}" for k, v in c["removed"].items()))
        if self.refinement:
            r = self.refinement
            lines.append(f"refinement: {'kept' if r['accepted'] else 'not kept'}, "
                         f"{r['start_value']:.6g} → {r['value']:.6g} in {r['iterations']} "
                         f"IPOPT iterations ({r['status']})")
        if self.coverage:
            c = self.coverage
            lines.append(f"coverage of joint {c['joint']}: bins {c['bins_used']} used, "
                         f"{c['min_bins']} required: {'met' if c['met'] else 'NOT met'}")
        if self.clearances:
            mm, pair = min(self.clearances)
            lines.append(f"clearance: every pose keeps ≥ {mm:.1f} mm ({pair} the closest)")
        if self.detectability:
            d0 = self.detectability[0]
            lines += ["", f"What these poses can reveal (χ² score test at α = {d0.alpha:g}, "
                          f"power {d0.power:.0%}, the model's own parameters estimated too):"]
            lines += [f"  {d}" for d in self.detectability]
        lines += [*self.notes, "", f"{'parameter':<22}{'predicted std':>14}  unit"]
        lines += [f"{n:<22}{s:14.4g}  {u}" for n, (s, u) in self.predicted_std.items()]
        return "\n".join(lines)

    def to_dict(self) -> dict:
        return {"format": FORMAT, "model": self.model, "criterion": self.criterion,
                "value": self.value, "bound": self.bound, "efficiency": self.efficiency,
                "poses": self.poses(),
                "predicted_std": [{"name": n, "std": s, "unit": u}
                                  for n, (s, u) in self.predicted_std.items()],
                "constraints": self.constraints, "notes": list(self.notes),
                "efficiencies": self.efficiencies, "criteria": self.criteria,
                "equivalence": self.equivalence, "candidates": self.candidates,
                "refinement": self.refinement, "coverage": self.coverage,
                "versus_random": self.versus_random, "sigma_mm": self.sigma_mm,
                "stages": self.stages,
                "detectability": [d.to_dict() for d in self.detectability],
                "robot": self.robot.to_dict(), "tool": self.tool.to_dict()}

    def to_json(self, path=None) -> str:
        """JSON text; also written to ``path`` when given."""
        return write_json(self.to_dict(), path)

    @classmethod
    def from_dict(cls, d: dict) -> "DesignResult":
        robot = Robot.from_dict(d["robot"])
        rows = [(p["pose"], p["q_deg"], w, _approach(p, robot.n_joints))
                for p in d["poses"] for w in p["wrenches"]]
        cfg = Configurations.from_arrays(np.array([r[1] for r in rows]) / robot.display_factors,
                                         np.array([r[2] for r in rows]),
                                         pose=[r[0] for r in rows],
                                         approach=np.array([r[3] for r in rows], float))
        return cls(robot, Tool.from_dict(d["tool"]), d["model"], cfg, d["criterion"],
                   float(d["value"]), float(d["bound"]), float(d["efficiency"]),
                   {r["name"]: (r["std"], r["unit"]) for r in d["predicted_std"]},
                   d.get("constraints", {}), tuple(d.get("notes", ())),
                   *(d.get(k, {}) for k in ("efficiencies", "criteria", "equivalence",
                                            "candidates", "refinement", "coverage",
                                            "versus_random")),
                   sigma_mm=None if d.get("sigma_mm") is None else float(d["sigma_mm"]),
                   clearances=tuple((float(p["clearance_mm"]), p["clearance_pair"])
                                    for p in d["poses"] if "clearance_mm" in p),
                   stages=d.get("stages", {}),
                   detectability=tuple(Detectability.from_dict(r)
                                       for r in d.get("detectability", ())))

    @classmethod
    def from_json(cls, path) -> "DesignResult":
        """Read a design file written by :meth:`to_json`."""
        return cls.from_dict(read_json(path, FORMAT, "doe_calib design file"))


def _approach(pose: dict, n_joints: int) -> list:
    """A pose entry's planned approach directions (N values of 1, -1, 0; all 0 when absent)."""
    approach = pose.get("approach", [0] * n_joints)
    if not (isinstance(approach, list) and len(approach) == n_joints
            and all(a in (-1, 0, 1) for a in approach)):
        raise DataError(f"pose {pose.get('pose')!r}: \"approach\" must be a list of {n_joints} "
                        f"values 1 (joint reached moving up), -1 (moving down) or 0 (no "
                        f"requirement), got {approach!r}")
    return approach
