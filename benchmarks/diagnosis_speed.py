"""(h) ``diagnose`` and ``refine`` in-process, and the ``refine`` command (issue 22): CPU time.

Two campaigns of the built-in KR 270: the issue's 60 poses (each unloaded and
with 250 kg, 3 markers: 360 readings, simulated with the full model), diagnosed
with the full model and refined from ``joint_offset+geometry``; and a
UR10-size real campaign, 2 800 random poses, unloaded, one marker (2 800
readings, 8 400 coordinates) with a hidden cyclic error of joint 3 (2 per
revolution), refined from ``joint_offset+geometry``. Each call is timed once
after the starting fit, in this process (start-up and imports excluded), by CPU
time (user + system: what a loaded machine does not inflate) and wall time, BLAS
on one thread as the commands run it (on a loaded machine OpenBLAS's spinning
threads multiply the CPU time of a QR: this section's figures before this round
were taken so). The "before" figures are the same calls at this round's start
(commit 87363ab), measured side by side at the same load; the 100 000-reading
diagnose is section (f). The ``refine`` command then runs on both campaigns (written as
measurement CSVs) in its own process, as a user runs it: start-up, imports,
reading, the starting fit, refine, the result files and the figure; one untimed
run first fills the bytecode cache. Its "before" is this round's start (commit
87363ab, measured side by side at the same load).
"""
from __future__ import annotations

import os
import resource
import subprocess
import sys
import tempfile
import time
import warnings
from pathlib import Path

import numpy as np

from doe_calib import Configurations, Robot, Tool, build_model, examples, simulate
from doe_calib.diagnosis import diagnose
from doe_calib.diagnosis.refine import refine
from doe_calib.estimation.identify import identify_quietly
from doe_calib.io.csv_files import write_measurements
from doe_calib.model.loads import hanging_mass_wrench
from doe_calib.model.simulate import random_configurations, random_truth
from doe_calib.runtime.threads import single_threaded_blas

from ._common import MODEL_6R, Row, Section

SIGMA = 2e-5  # m
#: CPU seconds of each case at this round's start (commit 87363ab, BLAS on one thread,
#: side by side with the code after, load ≈ 5). Commit 1bdc1d4 (before the candidate batch,
#: BLAS on every core) took 3.34, 21.8 and 39.4 s.
RECORDED = {"diagnose60": 0.314, "refine60": 3.95, "refine2800": 3.06}
#: The issue's goals for the whole command (s); the in-process call must leave room for
#: start-up, reading and writing.
GOALS = {"diagnose60": 1.5, "refine60": 2.5, "refine2800": 5.0}
CASES = {"diagnose60": "diagnose, 60 poses (360 readings), full model",
         "refine60": "refine, 60 poses, from joint_offset+geometry",
         "refine2800": "refine, 2 800 poses × 1 marker (8 400 coordinates), from "
                       "joint_offset+geometry"}
#: The refine command in its own process at this round's start (commit 87363ab): (wall s on
#: a quiet machine, section (g), where timed; CPU s, the mean of four runs side by side with
#: the code after at load 5–7); the goals (s) are the issue's.
COMMAND_BEFORE = {"refine60": (5.5, 5.62), "refine2800": (None, 5.36)}
COMMAND_GOALS = {"refine60": 2.5, "refine2800": 5.0}


def _cpu() -> float:
    r = resource.getrusage(resource.RUSAGE_SELF)
    return r.ru_utime + r.ru_stime


def _campaign60(robot, tool):
    true = build_model(robot, tool, MODEL_6R)
    rng = np.random.default_rng(1)
    truth = random_truth(true, rng)
    q = np.repeat(random_configurations(robot, 60, rng), 2, axis=0)
    w = np.zeros((120, 6))
    w[1::2] = hanging_mass_wrench(true, truth, q[1::2], 250.0, (0.0, 0.0, 0.2))
    cfg = Configurations.from_arrays(q, w, pose=np.repeat(np.arange(60) + 1, 2))
    return simulate(true, truth, cfg, SIGMA, rng)


def _campaign2800(robot, tool):
    true = build_model(robot, tool, "joint_offset+geometry+cyclic(j3,harmonics=2)")
    rng = np.random.default_rng(2)
    truth = random_truth(true, rng)
    q = random_configurations(robot, 2800, rng)
    cfg = Configurations.from_arrays(q, np.zeros((2800, 6)), pose=np.arange(2800) + 1)
    return simulate(true, truth, cfg, SIGMA, rng, markers=tool.names[:1])


def _timed(call, *args) -> tuple:
    load, c0, t0 = os.getloadavg()[0], _cpu(), time.perf_counter()
    out = call(*args)
    return _cpu() - c0, time.perf_counter() - t0, load, out


def _command(robot, tool, meas, tmp: Path, name: str) -> tuple:
    """Wall and CPU time (s) of ``doe-calib refine`` on ``meas`` in its own process, after one
    untimed run (bytecode cache), and the exit status."""
    data = tmp / f"{name}.csv"
    write_measurements(data, meas, robot, tool)
    argv = [sys.executable, "-m", "doe_calib", "refine", "--robot", examples.ROBOT_URDF,
            "--tool", examples.TOOL_YAML, "--data", data, "--sigma", SIGMA * 1e3,
            "--model", "joint_offset+geometry", "--out", tmp / f"{name}.json"]
    env = dict(os.environ, DOE_CALIB_CACHE=str(tmp / "cache"))
    env.pop("PYTHONDONTWRITEBYTECODE", None)  # as on a user's machine
    subprocess.run(list(map(str, argv)), env=env, capture_output=True)
    before = resource.getrusage(resource.RUSAGE_CHILDREN)
    t0 = time.perf_counter()
    rc = subprocess.run(list(map(str, argv)), env=env, capture_output=True).returncode
    wall = time.perf_counter() - t0
    after = resource.getrusage(resource.RUSAGE_CHILDREN)
    cpu = after.ru_utime + after.ru_stime - before.ru_utime - before.ru_stime
    return wall, cpu, rc


def _command_rows(robot, tool, campaigns: dict) -> list:
    rows = []
    with tempfile.TemporaryDirectory(prefix="doe_calib_refine_") as tmp:
        for name, meas in campaigns.items():
            load = os.getloadavg()[0]
            wall, cpu, rc = _command(robot, tool, meas, Path(tmp), name)
            (wall0, cpu0), goal = COMMAND_BEFORE[name], COMMAND_GOALS[name]
            # judged on wall time, as the issue measures: the command's threads and its
            # figure process make its CPU time exceed its wall time on two cores
            verdict = "met" if wall <= goal else ("met within the 20 % noise"
                                                  if wall <= 1.2 * goal else "NOT met")
            busy = "" if load < (os.cpu_count() or 1) else " (a loaded machine: inflated)"
            rows.append(Row(f"doe-calib {CASES[name]}, own process", wall, "s",
                            cpu / cpu0, f"CPU {cpu:.2f} s, before {cpu0:g} s CPU"
                            + (f" ({wall0:g} s wall, quiet)" if wall0 else "") + "; "
                            f"load {load:.1f}{busy}; goal ≤ {goal:g} s: "
                            f"{verdict}" + (f"; exit status {rc}" if rc else "")))
    return rows


def run(quick: bool = False) -> Section:
    blas = single_threaded_blas()  # noqa: F841 (kept alive: the limit lasts while it does)
    robot, tool = Robot.from_urdf(examples.ROBOT_URDF), Tool.from_yaml(examples.TOOL_YAML)
    meas60, meas2800 = _campaign60(robot, tool), _campaign2800(robot, tool)
    full, start = build_model(robot, tool, MODEL_6R), build_model(robot, tool,
                                                                  "joint_offset+geometry")
    calls = {"diagnose60": (full, meas60, diagnose),
             "refine60": (start, meas60, lambda m, d, f: refine(m, d, fit=f)),
             "refine2800": (start, meas2800, lambda m, d, f: refine(m, d, fit=f))}
    if quick:
        calls.pop("refine2800")
    rows, found = [], []
    for name, (model, meas, call) in calls.items():
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            fit = identify_quietly(model, meas)
            cpu, wall, load, out = _timed(call, model, meas, fit)
        before, goal = RECORDED[name], GOALS[name]
        rows.append(Row(CASES[name], cpu, "s CPU", cpu / before,
                        f"before {before:g} s CPU; wall {wall:.2f} s; load {load:.1f}; "
                        f"the whole command's goal ≤ {goal:g} s"))
        found.append((CASES[name], f"proposed: {out.proposed}" if name.startswith("diag")
                      else " → ".join(s.added or "start" for s in out.steps)))
    commands = {"refine60": meas60} if quick else {"refine60": meas60, "refine2800": meas2800}
    rows += _command_rows(robot, tool, commands)
    notes = ("one run per case after the starting fit; CPU time of this process "
             "(BLAS on one thread); ratio = after ÷ before (CPU); the command rows are the "
             "command's wall time, judged against the issue's goal as the issue measures.",
             "before/after give the same verdicts, proposals and added effects; their "
             "numbers agree to rounding (~1e-13 relative).",
             "the chosen candidates fitted in threads (diagnosis/candidate_scoring.py), each "
             "grown model built while the others fit; the figure drawn in a child process.")
    return Section("(h) diagnose and refine, in-process and the refine command", tuple(rows),
                   "this round's start, same calls", notes,
                   tables=(("what each call found", ("case", "effects"), tuple(found)),))
