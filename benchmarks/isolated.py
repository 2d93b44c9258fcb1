"""Run one benchmark in a new interpreter, so that its peak memory is its own."""
from __future__ import annotations

import importlib
import logging
import multiprocessing
import resource
from concurrent.futures import ProcessPoolExecutor
from dataclasses import replace


def measured(name: str, quick: bool):
    """Run ``benchmarks.<name>`` in this process; its section with the peak memory noted."""
    logging.basicConfig(level=logging.WARNING)
    section = importlib.import_module(f"benchmarks.{name}").run(quick)
    if section.measures_memory:
        return section
    peak_mb = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024.0  # Linux: KiB
    return replace(section, notes=section.notes + (
        f"peak memory of the process that ran this benchmark: {peak_mb:.0f} MB (resident set, "
        f"including Python, CasADi, Pinocchio and the models)",))


def isolated(name: str, quick: bool):
    """:func:`measured` in a freshly spawned process."""
    with ProcessPoolExecutor(1, mp_context=multiprocessing.get_context("spawn")) as pool:
        return pool.submit(measured, name, quick).result()
