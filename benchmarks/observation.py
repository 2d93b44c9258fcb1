"""(a) Observation matrix: cost per pose, SX virtual machine against compiled code.

The full 6R model (joint_offset+geometry+joint_compliance, 3 markers, 69
parameters): ``observation_matrix`` gives the 9 marker coordinates and their
9×69 Jacobian per pose. Compiled, it runs on SIMD lanes (two or four poses
per instruction, :mod:`doe_calib.model.simd_code`); CasADi's own scalar code,
one pose per call (what ran before), is compiled here too and timed beside
it, at the same load. Pinocchio's ``framesForwardKinematics`` +
``computeFrameJacobian`` (a Python loop over poses) is shown for scale only:
it gives the flange pose and its 6×6 Jacobian in q, not a 9×69 parameter
Jacobian through compliance.
"""
from __future__ import annotations

import os
import statistics
import tempfile
import time
from dataclasses import replace

import numpy as np

from doe_calib import Configurations, observation_matrix
from doe_calib.model.compiled import compile_function
from doe_calib.model.simd_code import simd_lanes
from doe_calib.model.simulate import random_configurations, random_truth

from ._common import Row, Section, models

#: The issue's goal: compiled ≤ 4× Pinocchio's FK + frame Jacobian per pose.
GOAL_RATIO = 4.0
#: Recorded before this round (results/benchmarks.md, 2026-12-02T00:34:53, load 1.0):
#: compiled, CasADi's scalar code, one pose per call.
BEFORE_US, BEFORE_PINOCCHIO_US = 7.40, 1.31
PINOCCHIO = "Pinocchio FK + 6×6 frame Jacobian, Python loop (scale only)"


def _cpu_us(fn, n_poses: int, repeats: int) -> float:
    """Median CPU time (user + sys of this process) of ``fn()`` per pose, µs."""
    fn()
    times = []
    for _ in range(repeats):
        t0 = time.process_time()
        fn()
        times.append(time.process_time() - t0)
    return statistics.median(times) / n_poses * 1e6


def _pinocchio_loop(robot_urdf, q):
    import pinocchio as pin

    pm = pin.buildModelFromUrdf(robot_urdf)
    pd = pm.createData()
    frame = pm.getFrameId("tool0")

    def loop():
        for qi in q:
            pin.framesForwardKinematics(pm, pd, qi)
            pin.computeFrameJacobian(pm, pd, qi, frame)

    return loop


def _casadis_code(model):
    """The compiled model with CasADi's own scalar observation code, one pose per call."""
    old = os.environ.get("DOE_CALIB_CACHE")
    with tempfile.TemporaryDirectory(prefix="doe_calib_bench_") as cache:
        os.environ["DOE_CALIB_CACHE"] = cache
        try:
            scalar = compile_function(model.observation)
        finally:
            if old is None:
                del os.environ["DOE_CALIB_CACHE"]
            else:
                os.environ["DOE_CALIB_CACHE"] = old
    return replace(model, observation=scalar, observation_lanes=None)


def run(quick: bool = False, n_poses: int = 1000) -> Section:
    """Observation-matrix cost per pose (µs CPU) for ``n_poses`` random loaded poses."""
    from doe_calib import examples

    ms = models()
    rng = np.random.default_rng(2024)
    q = random_configurations(ms.robot6, n_poses, rng)
    wrench = rng.normal(size=(n_poses, 6)) * ([1000.0] * 3 + [100.0] * 3)
    cfg = Configurations.from_arrays(q, wrench)
    values = random_truth(ms.vm6, rng)
    repeats = 5 if quick else 31
    scalar6 = _casadis_code(ms.vm6) if ms.compiled else ms.vm6
    cases = (("SX virtual machine", ms.vm6),
             ("compiled, CasADi's scalar code, one pose per call (before)", scalar6),
             ("compiled", ms.compiled6))
    _, b_vm = observation_matrix(ms.vm6, values, cfg)
    agree = max(float(np.abs(b_vm - observation_matrix(m, values, cfg)[1]).max())
                for _, m in cases[1:])
    load = os.getloadavg()[0] if hasattr(os, "getloadavg") else float("nan")
    figures = {}
    for _ in range(3 if not quick else 1):  # interleaved, so each sees the same load
        for tag, model in cases:
            figures.setdefault(tag, []).append(
                _cpu_us(lambda m=model: observation_matrix(m, values, cfg), n_poses, repeats))
        figures.setdefault(PINOCCHIO, []).append(
            _cpu_us(_pinocchio_loop(examples.ROBOT_URDF, q), n_poses, repeats))
    figures = {tag: min(v) for tag, v in figures.items()}
    ref = figures["compiled"]
    notes_row = {"compiled": f"{simd_lanes()} poses per instruction (SIMD code)",
                 cases[1][0]: f"recorded before: {BEFORE_US:g} µs/pose at load 1.0"}
    out = tuple(Row(case, us, "µs/pose CPU", us / ref, notes_row.get(case, ""))
                for case, us in figures.items())
    pin_us = figures[PINOCCHIO]
    ratio = ref / pin_us
    verdict = "met" if ratio <= GOAL_RATIO else "NOT met"
    notes = (
        f"{n_poses} random poses with random wrenches; B is 9×{b_vm.shape[-1]} per pose; "
        f"compiled (both codes) and virtual machine agree to {agree:.1e}.",
        f"CPU time of this process (user + sys), best of interleaved medians; load average "
        f"{load:.1f} at the start.",
        f"virtual machine / compiled: {figures['SX virtual machine'] / ref:.1f}×; "
        f"SIMD / CasADi's scalar code: {ref / figures[cases[1][0]]:.2f} "
        f"(before: {BEFORE_US:g} µs/pose = {BEFORE_US / BEFORE_PINOCCHIO_US:.1f}× Pinocchio's "
        f"recorded {BEFORE_PINOCCHIO_US:g} µs; now {ref / BEFORE_PINOCCHIO_US:.1f}× that).",
        f"goal compiled ≤ {GOAL_RATIO:g}× Pinocchio (Pinocchio computes far less: a 6×6 "
        f"Jacobian in q, no parameters, no compliance): {verdict} ({ref:.2f} µs/pose = "
        f"{ratio:.1f}×)" + ("; no C compiler, so these figures are the virtual machine's"
                            if not ms.compiled else ""),
    )
    return Section("(a) observation matrix per pose, 6R full model", out, "compiled", notes)
