"""What the benchmarks share: the models, the designs, timing and result rows."""
from __future__ import annotations

import os
import statistics
import tempfile
import time
import warnings
from contextlib import contextmanager
from dataclasses import dataclass, field
from functools import lru_cache

import numpy as np

from doe_calib import Configurations, Robot, Tool, build_model, examples
from doe_calib.model.simulate import random_configurations

#: The full 6R model of every 6R benchmark: all parameter blocks.
MODEL_6R = "joint_offset+geometry+joint_compliance"


@dataclass(frozen=True)
class Row:
    """One measured figure; ``ratio`` is value / the section's reference figure."""

    case: str
    value: float
    unit: str
    ratio: float | None = None
    note: str = ""


@dataclass(frozen=True)
class Section:
    """One benchmark's results: rows, what the ratios divide by, notes in words,
    optional further tables, each ``(caption, header, rows)`` of preformatted cells, and
    whether it measures peak memory itself (else the runner notes its process's peak)."""

    title: str
    rows: tuple
    reference: str = ""
    notes: tuple = field(default_factory=tuple)
    tables: tuple = field(default_factory=tuple)
    measures_memory: bool = False


@dataclass(frozen=True)
class Models:
    """The benchmark models, each on the SX virtual machine (``vm``) and compiled."""

    robot6: Robot
    vm6: object
    compiled6: object
    robot3: Robot
    vm3: object
    compiled3: object
    compile_seconds: float
    reload_seconds: float
    compile3_seconds: float

    @property
    def compiled(self) -> bool:
        return self.compiled6.observation.is_a("External", True)


@contextmanager
def cold_cache():
    """An empty native-code cache (``DOE_CALIB_CACHE``) for the block, the old one after."""
    old = os.environ.get("DOE_CALIB_CACHE")
    with tempfile.TemporaryDirectory(prefix="doe_calib_bench_") as cache:
        os.environ["DOE_CALIB_CACHE"] = cache
        try:
            yield cache
        finally:
            if old is None:
                del os.environ["DOE_CALIB_CACHE"]
            else:
                os.environ["DOE_CALIB_CACHE"] = old


@lru_cache(maxsize=1)
def models() -> Models:
    """Build every model once; the compiled ones into a fresh cache, so the cost is measured.

    The compile time (cold cache) and the reload time (same model, warm cache)
    are recorded here and kept out of every other timing.
    """
    robot6, tool6 = Robot.from_urdf(examples.ROBOT_URDF), Tool.from_yaml(examples.TOOL_YAML)
    robot3 = Robot.from_urdf(examples.THREE_DOF_URDF)
    tool3 = Tool.from_yaml(examples.THREE_DOF_TOOL_YAML)
    with cold_cache():
        t0 = time.perf_counter()
        compiled6 = build_model(robot6, tool6, MODEL_6R, compile=True)
        t1 = time.perf_counter()
        compiled6 = build_model(robot6, tool6, MODEL_6R, compile=True)
        t2 = time.perf_counter()
        compiled3 = build_model(robot3, tool3, "joint_offset+geometry", compile=True)
        t3 = time.perf_counter()
    # the loaded libraries stay mapped in this process after the directory is gone
    return Models(robot6, build_model(robot6, tool6, MODEL_6R), compiled6, robot3,
                  build_model(robot3, tool3, "joint_offset+geometry"), compiled3,
                  t1 - t0, t2 - t1, t3 - t2)


def loaded_design(robot, n_poses: int, rng, force: float = 2500.0, moment: float = 300.0):
    """``n_poses`` random poses, each unloaded and under a load of the given size (N, N·m)."""
    q = random_configurations(robot, n_poses, rng)
    w = np.zeros((2 * n_poses, 6))
    d = rng.normal(size=(n_poses, 6))
    w[1::2, :3] = force * d[:, :3] / np.linalg.norm(d[:, :3], axis=1, keepdims=True)
    w[1::2, 3:] = moment * d[:, 3:] / np.linalg.norm(d[:, 3:], axis=1, keepdims=True)
    return Configurations.from_arrays(np.repeat(q, 2, axis=0), w,
                                      pose=np.repeat(np.arange(n_poses), 2))


def median_seconds(fn, repeats: int) -> float:
    """Median wall time of ``fn()`` over ``repeats`` calls, after one untimed warm-up."""
    fn()
    times = []
    for _ in range(repeats):
        t0 = time.perf_counter()
        fn()
        times.append(time.perf_counter() - t0)
    return statistics.median(times)


@contextmanager
def quiet():
    """Silence the expected identifiability/conditioning warnings of simulated campaigns."""
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        yield
