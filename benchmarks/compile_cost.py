"""The one-off cost of compiling the models, and the machine the figures come from."""
from __future__ import annotations

import os
import platform

import casadi as ca

from doe_calib.model.compiled import FLAGS, find_compiler

from ._common import Row, Section, models


def run(quick: bool = False) -> Section:
    ms = models()
    rows = (Row("6R full model: compile markers/observation/point/point_robot (cold cache)",
                ms.compile_seconds, "s"),
            Row("6R full model: build again (libraries loaded from the cache)",
                ms.reload_seconds, "s"),
            Row("3-DOF model: compile (cold cache)", ms.compile3_seconds, "s"))
    load = os.getloadavg()[0] if hasattr(os, "getloadavg") else float("nan")
    notes = (f"compiler {find_compiler()} {' '.join(FLAGS)}; CasADi {ca.__version__}; "
             f"{platform.processor() or platform.machine()}, {os.cpu_count()} CPUs, "
             f"load average {load:.1f} at the start",
             "compiled: " + ("yes" if ms.compiled else "NO (no working C compiler; the "
                             "'compiled' rows below are the virtual machine)"),
             "these costs are kept out of every timing below.")
    return Section("compilation (one-off)", rows, "", notes)
