"""(i) The collision check of a program's moves (issue 22, the `export` row): dense vs skipping.

The program is the `export` row's of section (g): a 30-pose UR5 design in the UR5 example
cell (table, wall, floor, tracker), with 3 kg on the flange in its second load case, written
as URScript. Every move the export checks (straight moves, routes tried, planned paths
re-checked) is recorded once, then checked again in this process at ≤ 1° steps, first with
every pair tested at every pose (``Workspace(cm, bounded=False)``, what the check did before),
then with the poses skipped where the lower bound on a pair's distance proves it clear
(collision/bounds.py), on the meshes, then with each pair tested on its convex hulls first
(collision/hulls.py). All give the same first pose and pair for every move (checked here).
The moves the export proves no path can make (collision/passage.py) are searched again as
before, by the planner, and proven again. On random poses of the same cell, the screening of a
pose (``too_close``: free poses, poses hit) and the planner's check of a state (any pair closer
than its move margin) are timed on the meshes (before) and with the hulls first (now), with
the same answers; so is the tracker beams' screening of the free ones (``screen_beams``), against
its time recorded before it judged a chunk of poses at once in the joints' frames.
CPU time (user + system) is what a loaded machine does not inflate. The `export` command
itself, in its own process, is timed too (before: recorded in issue 22 on this machine, and at
the start of this round of work).
"""
from __future__ import annotations

import contextlib
import importlib
import io
import os
import resource
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

from doe_calib import examples

from ._common import Row, Section
from .commands import ur5_urdf

#: The `export` row as recorded on this machine before this work, CPU s (wall 28.8 s), and goal.
RECORDED_EXPORT, GOAL = 28.4, 3.0
#: The `export` row at the start of this round (main 87363ab, quiet machine), CPU s.
ROUND_START = 18.45


def cpu_seconds() -> float:
    r = resource.getrusage(resource.RUSAGE_SELF)
    return r.ru_utime + r.ru_stime


def children_cpu() -> float:
    r = resource.getrusage(resource.RUSAGE_CHILDREN)
    return r.ru_utime + r.ru_stime


def ur5_design(tmp: Path, env) -> Path:
    (tmp / "tool.yaml").write_text(Path(examples.UR_TOOL_YAML).read_text(encoding="utf-8"))
    (tmp / "cell.yaml").write_text(Path(examples.UR5_CELL_YAML).read_text(encoding="utf-8"))
    subprocess.run([sys.executable, "-m", "doe_calib", "design", "--robot", str(ur5_urdf()),
                    "--tool", str(tmp / "tool.yaml"), "--poses", "30", "--load", "3@0,0,80:40",
                    "--candidates", "500", "--constraints", str(tmp / "cell.yaml"),
                    "--no-refine", "--seed", "1", "--out", str(tmp / "ur5.json")],
                   env=env, check=True, capture_output=True)
    return tmp / "ur5.json"


def timed_export(design: Path, tmp: Path, env) -> tuple[float, float]:
    """Wall and CPU time (s) of ``doe-calib export`` of ``design`` as URScript, own process."""
    before = children_cpu()
    t0 = time.perf_counter()
    subprocess.run([sys.executable, "-m", "doe_calib", "export", str(design), "--format",
                    "urscript", "--out", str(tmp / "timed"), "--allow-collisions"],
                   env=env, check=True, capture_output=True)
    return time.perf_counter() - t0, children_cpu() - before


@contextlib.contextmanager
def exported_ur5(prefix: str):
    """A temporary folder with the 30-pose UR5 design (:func:`ur5_design`) and its export
    timed (:func:`timed_export`): yields (folder, design file, wall s, CPU s)."""
    with tempfile.TemporaryDirectory(prefix=prefix) as tmp:
        tmp = Path(tmp)
        env = dict(os.environ, DOE_CALIB_CACHE=str(tmp / "cache"))
        design = ur5_design(tmp, env)
        yield (tmp, design, *timed_export(design, tmp, env))


@contextlib.contextmanager
def patched(original, replacement):
    """``original`` (a function) replaced in every loaded module that holds it, while the
    block runs."""
    name = original.__name__
    modules = [m for m in list(sys.modules.values())
               if m is not None and getattr(m, name, None) is original]
    for m in modules:
        setattr(m, name, replacement)
    try:
        yield
    finally:
        for m in modules:
            setattr(m, name, original)


def exported_here(design: Path, out: Path) -> None:
    """``doe-calib export`` of ``design`` run in this process, its moves checked here too (the
    command's worker processes would hide them from the recorders), quietly."""
    import doe_calib.cli.export  # noqa: F401  (imported now, so that its names are patched)
    import doe_calib.runtime.forked as forked
    from doe_calib.cli import main

    workers = forked.default_workers
    forked.default_workers = lambda: 1
    try:
        with contextlib.redirect_stdout(io.StringIO()), contextlib.redirect_stderr(io.StringIO()):
            main(["export", str(design), "--format", "urscript", "--out", str(out),
                  "--allow-collisions"])
    finally:
        forked.default_workers = workers


def _recorded_moves(design: Path, out: Path) -> tuple:
    """(model, qa, qb, margins, pairs) of every move the export of ``design`` checks, and
    (model, Pinocchio configuration) of every state its motion planner checks."""
    clearance = importlib.import_module("doe_calib.collision.clearance")
    planner = importlib.import_module("doe_calib.collision.planner")
    moves, states, check, state = [], [], clearance.check_segment, planner.first_too_close

    def recording(cm, qa, qb, margin=None, step=clearance.SEGMENT_STEP, workspace=None,
                  pairs=None):
        moves.append((cm, qa.copy(), qb.copy(), margin, pairs))
        return check(cm, qa, qb, margin, step, workspace, pairs)

    def recording_state(cm, ws, x):
        states.append((cm, x.copy()))
        return state(cm, ws, x)

    planner.first_too_close = recording_state
    try:
        with patched(check, recording):
            exported_here(design, out)
    finally:
        planner.first_too_close = state
    return moves, states


def _blocked_moves(design: Path, out: Path) -> list:
    """(model, qa, qb) of every move the export of ``design`` proves no path can make when
    its turns are chosen as before, blind to the values no path can pass (now they avoid
    them: the program has no such move)."""
    import doe_calib.export.safety as safety
    import doe_calib.export.turns as turns

    blocked, prove = [], safety.blocked_passage

    def proving(cm, qa, qb, *args):
        found = prove(cm, qa, qb, *args)
        if found is not None:
            blocked.append((cm, np.array(qa), np.array(qb)))
        return found

    with patched(prove, proving), patched(turns.blocked_turns, lambda cm, robot: ()):
        exported_here(design, out)
    return blocked


def _check_all(moves, bounded: bool, hulls: bool = True):
    from doe_calib.collision import Workspace, check_segment

    spaces = {}
    t0 = cpu_seconds()
    found = [check_segment(cm, qa, qb, margin, pairs=pairs,
                           workspace=spaces.setdefault(id(cm), Workspace(cm, bounded, hulls)))
             for cm, qa, qb, margin, pairs in moves]
    return cpu_seconds() - t0, [(c.samples, c.first, c.pair) for c in found]


#: Random poses of the cell each pose check is timed on.
POSES = 20000


def _pose_checks(cm, states, n: int = POSES) -> dict:
    """CPU µs per pose of ``too_close`` (free poses, poses hit) and per state of the planner's
    check (``states``, Pinocchio configurations, at the move margins), on the meshes and with
    the hulls first: name → (before, after), and the count of free poses. The answers are
    checked to be the same."""
    import pinocchio as pin

    from doe_calib.collision import Workspace, too_close
    from doe_calib.collision.hulls import first_too_close

    lo = np.where(np.isfinite(cm.lower), cm.lower, -np.pi)
    hi = np.where(np.isfinite(cm.upper), cm.upper, np.pi)
    q = np.random.default_rng(0).uniform(lo, hi, (n, len(lo)))
    meshes, hulls = Workspace(cm, hulls=False), Workspace(cm)
    truth = too_close(cm, q, workspace=meshes)
    out = {"free poses": int((truth < 0).sum())}
    for name, chosen in (("free", truth < 0), ("hit", truth >= 0)):
        times = []
        for ws in (meshes, hulls):
            t0 = cpu_seconds()
            found = too_close(cm, q[chosen], workspace=ws)
            times.append(1e6 * (cpu_seconds() - t0) / chosen.sum())
            if (found != truth[chosen]).any():
                raise AssertionError("the hull pre-check found other pairs than the meshes")
        out[name] = tuple(times)
    verdicts, times = [], []
    for ws in (meshes, hulls):
        ws.set_margins(cm.move_margins)
        t0 = cpu_seconds()  # the planner's state check (collision/planner.py, valid)
        if ws.hulls is None:
            free = [not pin.computeCollisions(cm.model, ws.data, cm.geometry, ws.geometry, x,
                                              True) for x in states]
        else:
            free = [first_too_close(cm, ws, x) < 0 for x in states]
        times.append(1e6 * (cpu_seconds() - t0) / len(states))
        verdicts.append(free)
    if verdicts[0] != verdicts[1]:
        raise AssertionError("the hull pre-check judged a planner's state otherwise")
    out["state"] = tuple(times)
    out["states"], out["free states"] = len(states), sum(verdicts[0])
    return out


#: ``screen_beams`` of a free pose of :func:`_beam_screening` before its batching in the joints'
#: frames (main 4e475f5, this machine), CPU µs.
BEAMS_BEFORE = 87.1


def _beam_screening(n: int = POSES) -> tuple:
    """CPU µs per pose of ``screen_beams`` (the tracker's beams, collision/beams.py) over the
    free poses among n random ones of the UR5 cell with 3 kg on the flange, before (recorded)
    and now; the count of free poses and the share of them blocked."""
    from doe_calib import Robot, Tool
    from doe_calib.collision import Workspace, build_collision_model, screen_beams, too_close
    from doe_calib.design import LoadCase, read_constraints

    robot, tool = Robot.from_urdf(ur5_urdf()), Tool.from_yaml(examples.UR_TOOL_YAML)
    cm = build_collision_model(robot, tool, [LoadCase(3.0, np.array([0, 0, 0.08]), 0.04)],
                               read_constraints(examples.UR5_CELL_YAML, robot, tool))
    lo = np.where(np.isfinite(cm.lower), cm.lower, -np.pi)
    hi = np.where(np.isfinite(cm.upper), cm.upper, np.pi)
    q = np.random.default_rng(0).uniform(lo, hi, (n, len(lo)))
    ws = Workspace(cm)
    q = q[too_close(cm, q, workspace=ws) < 0]
    screen_beams(cm, q[:10], ws)  # what the beams are checked against, computed once
    t0 = cpu_seconds()
    blocked = sum(b is not None for b in screen_beams(cm, q, ws))
    return BEAMS_BEFORE, 1e6 * (cpu_seconds() - t0) / len(q), len(q), blocked / len(q)


def _pose_rows(checks) -> tuple:
    free = checks["free poses"]
    rows = []
    for key, what in (("free", f"a free pose ({free} of {POSES} random poses of the cell)"),
                      ("hit", f"a pose hit ({POSES - free})"),
                      ("state", f"the planner's check of a state (the {checks['states']} "
                                f"its searches checked in the export, {checks['free states']} "
                                f"free)")):
        before, after = checks[key]
        check = "too_close of " if key != "state" else ""
        rows += [Row(f"{check}{what}, every pair on its meshes (before)", before, "µs CPU", 1.0),
                 Row("the same, each pair on its convex hulls first, on its meshes where they "
                     "are too close (now)", after, "µs CPU", after / before,
                     "the same answers")]
    return tuple(rows)


def _beam_rows(before, after, free, blocked) -> tuple:
    """The rows of :func:`_beam_screening`'s figures."""
    return (Row(f"screen_beams of a free pose ({free} of {POSES} random poses of the cell, "
                "3 kg on the flange), per pose Pinocchio's placements and numpy per (beam, "
                "body) pair (before: main 4e475f5, recorded)", before, "µs CPU", 1.0),
            Row("the same, every pair of a chunk of poses judged at once in the joints' "
                "frames, coal's test without numpy overhead (now)", after, "µs CPU",
                after / before, f"{blocked:.0%} of the poses blocked; the same verdicts "
                                f"(tests/test_collision_beams.py)"))


def _blocked_both_ways(blocked) -> tuple:
    """CPU s of proving each blocked move so, and of searching it (plan_move, as before)."""
    from doe_calib.collision import Workspace, blocked_passage, plan_move

    spaces = {}
    t0 = cpu_seconds()
    proofs = [blocked_passage(cm, qa, qb, workspace=spaces.setdefault(id(cm), Workspace(cm)))
              for cm, qa, qb in blocked]
    proved = cpu_seconds() - t0
    t0 = cpu_seconds()
    paths = [plan_move(cm, qa, qb, workspace=spaces[id(cm)], prove=False)
             for cm, qa, qb in blocked]
    searched = cpu_seconds() - t0
    if any(p is None for p in proofs) or any(p is not None for p in paths):
        raise AssertionError("a move proven blocked was not proven again, or a path was found")
    return proved, searched


def run(quick: bool = False) -> Section:
    load = os.getloadavg()[0]
    with exported_ur5("doe_calib_collision_") as (tmp, design, wall, cpu):
        moves, states = _recorded_moves(design, tmp / "recorded")
        blocked = _blocked_moves(design, tmp / "blind")
    dense_s, dense = _check_all(moves, bounded=False, hulls=False)
    meshes_s, meshes = _check_all(moves, bounded=True, hulls=False)
    fast_s, fast = _check_all(moves, bounded=True)
    if fast != dense or meshes != dense:
        raise AssertionError("the skipping check found other poses or pairs than the dense one")
    cm = next((cm for cm, _ in states), moves[0][0])
    checks = _pose_checks(cm, [x for model, x in states if model is cm])
    proved_s, searched_s = _blocked_both_ways(blocked)
    samples = sum(s for s, _, _ in dense)
    verdict = "met" if wall <= GOAL else ("met within the 20 % noise" if wall <= 1.2 * GOAL
                                          else "NOT met")
    rows = (Row(f"{len(moves)} moves checked at ≤ 1° ({samples} poses), every pair at every "
                "pose", dense_s, "s CPU", 1.0, f"{1e6 * dense_s / samples:.1f} µs per pose"),
            Row("the same moves, poses skipped where a pair is proven clear", meshes_s, "s CPU",
                meshes_s / dense_s, f"{1e6 * meshes_s / samples:.1f} µs per pose; same first "
                                    f"pose and pair for every move"),
            Row("the same, each pair tested on its convex hulls first, on its meshes where they "
                "are too close (now)", fast_s, "s CPU", fast_s / dense_s,
                f"{1e6 * fast_s / samples:.1f} µs per pose; same first pose and pair for every "
                f"move"),
            *_pose_rows(checks), *_beam_rows(*_beam_screening()),
            Row(f"{len(blocked)} moves no path can make (the program's turns chosen blind to "
                "them, as before), searched for by the planner: each search spends its whole "
                "budget", searched_s, "s CPU", 1.0, "no path found"),
            Row("the same moves proven blocked (collision/passage.py: a joint value every path "
                "passes, one pair always too close there)", proved_s, "s CPU",
                proved_s / searched_s, "neither routed nor searched; the program's turns "
                                       "now avoid them"),
            Row("export with the collision check, 30 poses (UR5 cell), own process", wall, "s",
                cpu / RECORDED_EXPORT, f"CPU {cpu:.2f} s (before {RECORDED_EXPORT:g} s CPU, "
                                       f"28.8 s wall; at this round's start {ROUND_START:g} s "
                                       f"CPU: × {cpu / ROUND_START:.2f}); goal ≤ {GOAL:g} s: "
                                       f"{verdict}"))
    notes = (f"load average (1 min) at the start: {load:.1f} on {os.cpu_count()} CPUs.",
             "the rows' ratio: CPU ÷ the dense check's CPU (moves; the candidate routes are "
             "looked at first on the pairs already found too close on their move: those "
             "checks are among these), CPU ÷ the meshes' CPU (pose and state checks), CPU ÷ "
             "the searches' CPU (blocked moves), CPU ÷ the recorded CPU (export); the motion "
             "planner's searches (OMPL RRT-Connect) test every pair at every state they check "
             "(the state rows; a state checked before in the same move answered from memory: "
             "section (j)): most of what the export still costs.")
    return Section("(i) the collision check of a program's moves", rows,
                   "every pair tested at every pose", notes)
