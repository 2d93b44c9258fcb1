"""What every design solver returns: one :class:`DesignOutcome` for the relaxation
(:func:`.relaxation.relax`), the exchange (:func:`.exchange.exact_design`) and the IPOPT
refinement (:func:`.pose_refinement.refine`), interchangeable steps of the pipeline: a design
measure over the points the solver was given, its criterion value and how it got there."""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from doe_calib.design.criteria import Criterion

STAGES = ("relaxation", "exchange", "refinement", "discovery")


@dataclass(frozen=True, eq=False)
class DesignOutcome:
    """One solver's design and how good it is.

    Attributes
    ----------
    stage : {"relaxation", "exchange", "refinement", "discovery"}
        The solver that made it.
    criterion : Criterion
    weights : ndarray, shape (K,)
        Weight of each point the solver was given: candidates for the
        relaxation (sum 1) and the exchange (1 on the chosen, else 0), the
        start poses for the refinement (all 1).
    value : float
        Criterion of Σ w_i M_i (for the relaxation, of the normalised M(w)).
    iterations : int
        Multiplicative iterations, exchange sweeps or IPOPT iterations.
    status : str
        How the solver ended, in words.
    p : int
        Number of (free) parameters.
    indices : ndarray of int, shape (N,), optional
        The exchange's chosen candidates, in pose order.
    ratio : float
        The relaxation's equivalence ratio c · max_i ψ_i ≥ 1 over every
        candidate: no design beats Φ(M(w)) by more (NaN for the other stages).
    q : ndarray, shape (N, n_joints), optional
        The refinement's poses (the refined ones if accepted, else the start), rad/m.
    start_value : float
        The refinement's criterion at its start poses (NaN otherwise).
    accepted : bool
        False when the refinement did not improve the criterion and was not kept.
    seconds : float
    stepped_back : int
        Refined poses that failed the re-check and were moved back toward their start.
    """

    stage: str
    criterion: Criterion
    weights: np.ndarray
    value: float
    iterations: int
    status: str
    p: int
    indices: np.ndarray | None = None
    ratio: float = np.nan
    q: np.ndarray | None = None
    start_value: float = np.nan
    accepted: bool = True
    seconds: float = 0.0
    stepped_back: int = 0

    @property
    def gap(self) -> float:
        """p (ratio − 1): for D the duality gap max_i d_i − p (relaxation)."""
        return self.p * (self.ratio - 1.0)

    def bound(self, n: int) -> float:
        """Upper bound on the criterion of any exact n-candidate design (relaxation only)."""
        if not np.isfinite(self.ratio):
            raise ValueError(f"the {self.stage} certifies no bound; the relaxation does")
        return self.criterion.bound_value(self.value, self.ratio, n, self.p)

    def summary(self) -> str:
        """One line: stage, criterion, value, iterations and status."""
        extra = f", equivalence ratio {self.ratio:.4g}" if np.isfinite(self.ratio) else ""
        return (f"{self.stage}: {self.criterion.name} criterion {self.value:.6g}{extra} after "
                f"{self.iterations} iterations ({self.status})")

    def to_dict(self) -> dict:
        """JSON-able: the stage's numbers (for the refinement the keys the design file uses)."""
        if self.stage == "refinement":
            return {"accepted": self.accepted, "status": self.status,
                    "iterations": self.iterations, "seconds": self.seconds,
                    "start_value": self.start_value, "value": self.value,
                    "stepped_back": self.stepped_back}
        out = {"criterion": self.criterion.name, "value": self.value,
               "iterations": self.iterations, "status": self.status,
               "support": int(np.count_nonzero(self.weights))}
        if np.isfinite(self.ratio):
            out["ratio"] = self.ratio
        return out
