"""The one-off cost of compiling the models, and the machine the figures come from."""
from __future__ import annotations

import os
import platform

import casadi as ca

from doe_calib.model import simd_code
from doe_calib.model.compiled import FLAGS, compile_functions, find_compiler

from ._common import Row, Section, cold_cache, models

#: Recorded before this round (results/benchmarks.md, 2026-12-02T00:34:47, load 1.2): the
#: 6R full model's four Functions compiled from a cold cache, wall time.
BEFORE_SECONDS = 4.84


def _compiler_cpu(function, source=None, lanes=2) -> float:
    """CPU seconds (user + sys) the C compiler takes for ``function``, cold cache."""
    with cold_cache():
        t0 = os.times()
        compile_functions([function], sources=[None if source is None
                                               else (source, simd_code.flags(lanes))])
        t1 = os.times()
    return t1.children_user + t1.children_system - t0.children_user - t0.children_system


def run(quick: bool = False) -> Section:
    ms = models()
    rows = [Row("6R full model: compile markers/observation/point/point_robot (cold cache)",
                ms.compile_seconds, "s", note=f"wall; before {BEFORE_SECONDS:g} s at load 1.2"),
            Row("6R full model: build again (libraries loaded from the cache)",
                ms.reload_seconds, "s"),
            Row("3-DOF model: compile (cold cache)", ms.compile3_seconds, "s")]
    if ms.compiled:
        f = ms.vm6.observation
        lanes = simd_code.simd_lanes()
        scalar = _compiler_cpu(f)
        simd = _compiler_cpu(f, simd_code.simd_source(f, lanes=lanes), lanes)
        rows += [Row("6R observation alone, CasADi's scalar code (before)", scalar, "s CPU",
                     note="the compiler's user + sys"),
                 Row(f"6R observation alone, SIMD code, {lanes} lanes (now)", simd, "s CPU",
                     ratio=simd / scalar, note="ratio ÷ CasADi's scalar code")]
    load = os.getloadavg()[0] if hasattr(os, "getloadavg") else float("nan")
    lanes = simd_code.simd_lanes()
    notes = (f"compiler {find_compiler()} {' '.join(FLAGS)} (SIMD code, {lanes} lanes: "
             f"{' '.join(simd_code.flags(lanes))}); CasADi {ca.__version__}; "
             f"{platform.processor() or platform.machine()}, {os.cpu_count()} CPUs, "
             f"load average {load:.1f} at the start",
             "compiled: " + ("yes" if ms.compiled else "NO (no working C compiler; the "
                             "'compiled' rows below are the virtual machine)"),
             "these costs are kept out of every timing below.")
    return Section("compilation (one-off)", tuple(rows), "", notes)
