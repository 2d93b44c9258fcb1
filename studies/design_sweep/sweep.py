"""The grid of the sweep, one optimal design per grid point, and the figures drawn from them.

A grid point is a :class:`SweepTask` (robot, tool, N, criterion, candidates,
refinement, seed): plain picklable values. :func:`design_point` builds the
model in the worker process (CasADi Functions do not pickle), runs
:func:`doe_calib.design.optimal.optimal_design` and returns plain numbers.
All tasks of one robot share one seed from :func:`doe_calib.runtime.parallel.task_seeds`
(common random numbers): the tools, pose counts and criteria of a robot are
compared on the same candidate poses, and no result depends on the engine.
"""
from __future__ import annotations

import time
import warnings
from dataclasses import asdict, dataclass
from functools import lru_cache

import numpy as np

from doe_calib import Robot, Tool, build_model, examples
from doe_calib.design import LoadCase
from doe_calib.design.optimal import optimal_design
from doe_calib.runtime.parallel import run_tasks, task_seeds

SIGMA = 3e-5  # tracker σ per coordinate, m (0.03 mm, as in the demo)
CANDIDATES = 3000
QUICK_CANDIDATES = 300


@dataclass(frozen=True)
class RobotSetup:
    """A robot of the sweep: URDF, model, load cases (kg, centre of mass m), tools, pose counts.

    ``tools`` maps a tool name to a tool YAML path or to ``{marker: [x, y, z]}`` in mm.
    """

    label: str
    urdf: str
    flange: str
    model: str
    loads: tuple
    tools: dict
    poses: tuple


#: The KR 270 tool's three markers moved from the 150 mm circle to a 100 mm one (mm).
SMALL_KR270_MARKERS = {"A": [100.0, 0.0, 120.0], "B": [-50.0, 86.6, 120.0],
                       "C": [-50.0, -86.6, 120.0]}

ROBOTS = {
    "kr270": RobotSetup("KR 270 (6R)", examples.ROBOT_URDF, "tool0",
                        "joint_offset+geometry+joint_compliance", ((250.0, (0.0, 0.0, 0.2)),),
                        {"r150": examples.TOOL_YAML, "r100": SMALL_KR270_MARKERS},
                        (8, 12, 15, 20, 30)),
    "three_dof": RobotSetup("3-DOF of eq. (21)", examples.THREE_DOF_URDF, "flange",
                            "joint_offset+geometry", (), {"r100": examples.THREE_DOF_TOOL_YAML},
                            (3, 5, 8)),
}
CRITERIA = ("D", "A")
#: The quick grid (tests): (robot, tool, N, criterion).
QUICK = (("three_dof", "r100", 3, "D"), ("three_dof", "r100", 8, "D"), ("kr270", "r100", 8, "D"))


@dataclass(frozen=True)
class SweepTask:
    """One grid point: what to design and with which seed (all picklable)."""

    robot: str
    tool: str
    n_poses: int
    criterion: str
    candidates: int
    refine: bool
    seed: int


def grid(quick: bool = False, candidates: int | None = None, refine: bool = False,
         seed: int = 2024) -> list[SweepTask]:
    """The sweep's tasks: robots × tools × N × criteria (or the :data:`QUICK` grid).

    ``candidates`` defaults to :data:`CANDIDATES` (:data:`QUICK_CANDIDATES`
    when quick); ``refine`` (the IPOPT refinement) is off by default: with it
    the full grid took about five times as long (on a busy machine).
    """
    candidates = candidates or (QUICK_CANDIDATES if quick else CANDIDATES)
    seeds = dict(zip(ROBOTS, task_seeds(seed, len(ROBOTS))))
    points = QUICK if quick else [(r, t, n, c) for r, s in ROBOTS.items() for t in s.tools
                                  for c in CRITERIA for n in s.poses]
    return [SweepTask(r, t, n, c, candidates, refine, seeds[r]) for r, t, n, c in points]


@lru_cache(maxsize=4)
def _model(robot: str, tool: str):
    setup = ROBOTS[robot]
    spec = setup.tools[tool]
    marker_tool = (Tool.from_yaml(spec) if isinstance(spec, str)
                   else Tool.from_markers(spec, setup.flange))
    return build_model(Robot.from_urdf(setup.urdf), marker_tool, setup.model)


def design_point(task: SweepTask) -> dict:
    """One optimal design → plain numbers (efficiencies, time, median std per parameter block).

    Returns
    -------
    dict
        The task's fields, ``d_efficiency`` and ``efficiency`` (the criterion's,
        both against the certified bound), ``random_equivalent`` (as precise,
        D criterion, as that many random poses; None when random designs are
        singular), ``median_std`` (``"block (unit)"`` → median predicted std of
        its free parameters, display units), ``refined``, ``warnings`` and
        ``seconds``.
    """
    setup, model = ROBOTS[task.robot], _model(task.robot, task.tool)
    loads = [LoadCase(mass, com) for mass, com in setup.loads]
    start = time.perf_counter()
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        res = optimal_design(model, task.n_poses, loads, candidates=task.candidates, sigma=SIGMA,
                             criterion=task.criterion, refine=task.refine,
                             rng=np.random.default_rng(task.seed))
    seconds = time.perf_counter() - start
    equivalent = res.versus_random.equivalent_poses
    return {**asdict(task), "model": model.spec, "d_efficiency": float(res.efficiencies["D"]),
            "efficiency": float(res.efficiency), "value": float(res.value),
            "bound": float(res.bound),
            "random_equivalent": None if equivalent is None else round(equivalent),
            "median_std": block_medians(model, res.predicted_std),
            "refined": bool(res.refinement.get("accepted", False)),
            "warnings": sorted({f"{w.category.__name__}: {w.message}" for w in caught}),
            "seconds": seconds}


def block_medians(model, predicted_std: dict) -> dict:
    """``"block (unit)"`` → median predicted std of the block's free parameters (display units)."""
    owner = {p.name: p.block for p in model.nominal().parameters}
    groups: dict = {}
    for name, (std, unit) in predicted_std.items():
        groups.setdefault(f"{owner[name]} ({unit})", []).append(std)
    return {key: float(np.median(v)) for key, v in groups.items()}


def marker_radius_mm(robot: str, tool: str) -> float:
    """RMS distance of the tool's markers from their centroid, mm."""
    pos = np.array(_model(robot, tool).tool.positions)
    return float(1e3 * np.sqrt(np.mean(np.sum((pos - pos.mean(0)) ** 2, axis=1))))


def run(quick: bool = False, candidates: int | None = None, refine: bool = False,
        seed: int = 2024, scheduler: str | None = None, workers: int | None = None,
        progress=None) -> dict:
    """The whole sweep through :func:`~doe_calib.runtime.parallel.run_tasks`; a JSON-ready dict."""
    tasks = grid(quick, candidates, refine, seed)
    start = time.perf_counter()
    points = run_tasks(design_point, tasks, scheduler, workers, progress)
    wall = time.perf_counter() - start
    ran = {(p["robot"], p["tool"]) for p in points}
    robots = {r: {"label": s.label, "model": s.model,
                  "loads": [LoadCase(m, c).spec() for m, c in s.loads],
                  "tools": {t: marker_radius_mm(r, t) for t in s.tools if (r, t) in ran}}
              for r, s in ROBOTS.items() if any(rr == r for rr, _ in ran)}
    return {"settings": {"quick": quick, "seed": seed, "sigma_mm": 1e3 * SIGMA,
                         "candidates": tasks[0].candidates, "refine": tasks[0].refine,
                         "engine": scheduler or f"local processes ({workers or 'all CPUs'})",
                         "wall_seconds": wall, "task_seconds": sum(p["seconds"] for p in points)},
            "robots": robots, "points": points, "findings": findings(points)}


def _group(points, robot, tool, criterion) -> list:
    return sorted((p for p in points if (p["robot"], p["tool"], p["criterion"])
                   == (robot, tool, criterion)), key=lambda p: p["n_poses"])


def findings(points) -> dict:
    """The figures the conclusions rest on.

    ``slopes``: per ``robot/tool/criterion`` and block, the log-log slope of the
    median std against N (−0.5 is the 1/√N of repeating the same poses).
    ``tool_price``: per robot, criterion and block, the std ratio of each other
    tool to the robot's first one in :data:`ROBOTS` (median over N).
    ``a_over_d``: per robot/tool and block, the std ratio of the A design to
    the D design (median over N), with the D-efficiencies of both.
    """
    out: dict = {"slopes": {}, "tool_price": {}, "a_over_d": {}}
    keys = list(dict.fromkeys((p["robot"], p["tool"], p["criterion"]) for p in points))
    for r, t, c in keys:
        g = _group(points, r, t, c)
        if len(g) > 1:
            n = np.log([p["n_poses"] for p in g])
            out["slopes"][f"{r}/{t}/{c}"] = {
                b: float(np.polyfit(n, np.log([p["median_std"][b] for p in g]), 1)[0])
                for b in _common(g)}
    for r, t, c in keys:
        first = next(tt for rr, tt, _ in keys if rr == r)
        if t != first:
            out["tool_price"][f"{r}/{t}÷{first}/{c}"] = _ratios(_group(points, r, t, c),
                                                                 _group(points, r, first, c))
        if c == "A" and (r, t, "D") in keys:
            a, d = _group(points, r, t, "A"), _group(points, r, t, "D")
            out["a_over_d"][f"{r}/{t}"] = {"std_ratio": _ratios(a, d),
                                           "d_efficiency_A": [p["d_efficiency"] for p in a],
                                           "d_efficiency_D": [p["d_efficiency"] for p in d]}
    return out


def _ratios(num, den) -> dict:
    """Block → median over common N of the std ratio ``num / den``."""
    by_n = {p["n_poses"]: p for p in den}
    pairs = [(p, by_n[p["n_poses"]]) for p in num if p["n_poses"] in by_n]
    return {b: float(np.median([a["median_std"][b] / d["median_std"][b] for a, d in pairs]))
            for b in _common([p for pair in pairs for p in pair])}


def _common(points) -> list:
    """Blocks present in every point (in the first point's order)."""
    if not points:
        return []
    return [b for b in points[0]["median_std"] if all(b in p["median_std"] for p in points)]
