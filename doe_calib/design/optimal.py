"""The design pipeline: candidates → relaxation (bound) → exact N-pose exchange → result."""
from __future__ import annotations

import numpy as np

from ..simulate import random_configurations
from .criteria import log_det
from .exchange import exact_d_design
from .problem import blocks_for, design_parameters, load_configurations
from .relaxation import information, relax_d
from .result import DesignResult

_RANDOM_DESIGNS = 100


def optimal_design(model, n_poses: int, loads=(), candidates: int = 20000, sigma: float = 2e-5,
                   margin: float = 0.02, params=None, rng=None, progress=None) -> DesignResult:
    """D-optimal N-pose design for ``model`` from random candidates within the joint limits.

    Parameters
    ----------
    model : Model
    n_poses : int
        Poses to measure; each is measured unloaded and under every load case.
    loads : sequence of LoadCase
    candidates : int
        Candidate poses drawn uniformly inside the joint limits.
    sigma : float
        Tracker σ per coordinate, m (scales the predicted std only).
    margin : float
        Fraction of each joint range kept clear at both ends.
    params : ParameterSet, optional
        Expected values (default nominal); parameters no candidate can
        identify are fixed.
    """
    rng = np.random.default_rng() if rng is None else rng
    params = model.nominal() if params is None else params
    q = random_configurations(model.robot, candidates, rng, margin=margin)
    params = design_parameters(model, params, q, loads, rng=rng)
    blocks = blocks_for(model, params, q, loads, sigma)
    relaxed = relax_d(blocks, progress=progress)
    chosen = exact_d_design(blocks, n_poses, relaxed.weights)
    m = information(blocks[chosen], np.ones(n_poses))
    p = m.shape[0]
    value, bound = log_det(m), relaxed.bound(n_poses)
    scale = params.scales[params.free]
    std = np.sqrt(np.diag(np.linalg.inv(m))) * scale
    free = [par for par, f in zip(params.parameters, params.free) if f]
    randoms = [log_det(information(blocks[rng.choice(len(blocks), n_poses, replace=False)],
                                   np.ones(n_poses))) for _ in range(_RANDOM_DESIGNS)]
    equivalent = n_poses * np.exp((value - np.median(randoms)) / p)
    cfg = load_configurations(model, params.values, q[chosen], loads)
    notes = (f"{n_poses} optimal poses are as precise (D criterion) as {equivalent:.0f} random "
             f"ones (median of {_RANDOM_DESIGNS} random designs of {n_poses} poses)",
             f"relaxation over {candidates} candidates: gap {relaxed.gap:.2g} after "
             f"{relaxed.iterations} iterations; {p} parameters designed for, "
             f"{int((~params.free).sum())} fixed as not identifiable by any candidate")
    constraints = {"joint_limits_deg_or_mm": [[lo * f, hi * f] for lo, hi, f in zip(
        model.robot.lower, model.robot.upper, model.robot.display_factors)],
        "margin_fraction": margin, "loads": [ld.spec() for ld in loads]}
    return DesignResult(model.robot, model.tool, model.spec, cfg, "D", value, bound,
                        float(np.exp((value - bound) / p)),
                        {par.name: (float(s * par.display_factor), par.display_unit)
                         for par, s in zip(free, std)}, constraints, notes)
