"""The paper's two-step alternation, kept for comparison with the joint estimator.

Step 1 estimates the base pose and the marker positions by linear least
squares with the robot parameters held; step 2 estimates the robot
parameters (geometry, compliance, ...) with base and markers held. The steps
repeat until neither moves. It converges to the same minimiser as the
``point`` estimator, usually in many more iterations, so the covariance
reported is the joint one at that minimiser.
"""
from __future__ import annotations

import numpy as np

from doe_calib.errors import SolverError
from doe_calib.estimation.assembly import finish
from doe_calib.estimation.preparation import prepare
from doe_calib.estimation.weighted_residuals import weighted_residual

_STEP1_BLOCKS = ("base", "markers")


def identify_two_step(model, measurements, params=None, max_iterations: int = 500,
                      tol: float = 1e-10, register: bool = True):
    """Alternate base+markers and robot-parameter least squares until converged.

    Parameters
    ----------
    max_iterations : int
        Alternations allowed (each is one step 1 and one step 2).
    tol : float
        Stop when every free parameter moves by less than ``tol`` × its scale.
    """
    params, notes, _, absorbed = prepare(model, measurements, params, register)
    blocks = np.array([p.block in _STEP1_BLOCKS for p in params.parameters])
    steps = [params.free & blocks, params.free & ~blocks]
    scale = params.scales
    values = params.values.copy()
    moved, done = np.inf, 0
    while done < max_iterations and not moved < tol:
        moved = 0.0
        for cols in steps:
            if not cols.any():
                continue
            r, jac = weighted_residual(model, measurements, values)
            step, *_ = np.linalg.lstsq(jac[:, cols], -r, rcond=None)
            values[cols] += step
            moved = max(moved, float(np.max(np.abs(step) / scale[cols])))
        if not np.all(np.isfinite(values)):
            raise SolverError("the two-step alternation diverged (non-finite parameters)")
        done += 1
    converged = moved < tol
    r, _ = weighted_residual(model, measurements, values, jacobian=False)
    convergence = {"converged": bool(converged), "iterations": done,
                   "evaluations": 2 * done, "status": int(converged),
                   "message": f"two-step: {done} alternations, last relative step "
                              f"{moved:.2g}", "residual_norm2": float(r @ r)}
    return finish(model, measurements, params.with_values(values), "two-step", convergence,
                  notes, absorbed=absorbed, stopped=None if converged else
                  f"two-step alternation stopped after {max_iterations} iterations; last "
                  f"relative step {moved:.2g} (tolerance {tol:g})")
