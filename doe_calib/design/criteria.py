"""Design criteria: objects that know everything a solver needs about one function of M.

A criterion is a pure function of the information matrix M of the free
parameters, already scaled by their typical sizes (``S M S`` with
``S = diag(scale)``) so that units do not decide the A and E criteria; D is
scale-invariant anyway. Larger is better. :class:`DOptimal`,
:class:`AOptimal`, :class:`EOptimal` and :class:`TaskOptimal` each carry
what every solver asks of it: its ``value`` (log det M, −tr M⁻¹, λ_min(M),
−tr(T M⁻¹ Tᵀ)), a concave cvxpy expression, the sensitivity and bounds of
the equivalence theorem below, rank-r updates for the exchange, log Φ as a
CasADi expression for IPOPT, and its name and words for reports.

The information function Φ is concave and positively homogeneous of degree 1
((det M)^(1/p), 1/tr M⁻¹, λ_min, 1/tr(T M⁻¹ Tᵀ)), which makes efficiencies
ratios and gives the equivalence theorem its general form: for candidates
with information M_i, normalised weights w and M = Σ w_i M_i, every design ξ
over the candidates has

    Φ(M(ξ)) ≤ c · max_i tr(H M_i) · Φ(M),

with the sensitivity matrix H and factor c of ``sensitivity``
(``Σ_i w_i tr(H M_i) = 1``; ψ_i = tr(H M_i) ≤ 1 for all i is the optimality
condition: d_i = tr(M⁻¹M_i) ≤ p for D). The functions at the end
(:func:`criterion`, :func:`efficiency` …) take a criterion name or object.

Examples
--------
>>> m = np.diag([4.0, 1.0])
>>> [round(criterion(c).value(m), 4) for c in ("D", "A", "E")]
[1.3863, -1.25, 1.0]
"""
from __future__ import annotations

from dataclasses import dataclass
from functools import partial
from typing import ClassVar

import casadi as ca
import numpy as np

CRITERIA = ("D", "A", "E", "task")

#: Order k of the smooth surrogate (tr M^-k)^(-1/k) of λ_min used for E.
E_ORDER = 32


def log_det(m: np.ndarray) -> float:
    """D: log det M (−inf when singular)."""
    sign, value = np.linalg.slogdet(m)
    return float(value) if sign > 0 else -np.inf


@dataclass(frozen=True, eq=False)
class Criterion:
    """A design criterion: a function of the scaled information M, larger is better.

    Subclasses set ``name``, ``words`` (what the criterion asks for, for
    reports), ``statistic`` (the equivalence-theorem statistic) and
    ``power`` (the exponent λ of the multiplicative relaxation step
    ``w_i ← w_i ψ_i^λ``, the value known to increase the criterion
    monotonically, Yu 2010). Build one with :func:`criterion`.
    """

    name: ClassVar[str]
    words: ClassVar[str]
    statistic: ClassVar[str]
    power: ClassVar[float] = 0.5

    @classmethod
    def from_name(cls, name, task: np.ndarray | None = None) -> "Criterion":
        """The criterion called ``name`` (one of :data:`CRITERIA`), or ``name`` if a Criterion.

        ``task`` (rows, p) is the task matrix of :class:`TaskOptimal`.
        Raises ValueError for an unknown name or the task criterion without task.
        """
        if isinstance(name, Criterion):
            return name
        check(name, task)
        if name == "task":
            return TaskOptimal(np.asarray(task, float))
        return {"D": DOptimal, "A": AOptimal, "E": EOptimal}[name]()

    def __str__(self) -> str:
        return self.name

    def value(self, m: np.ndarray) -> float:
        """The criterion of M (−inf when M is singular); here −tr(R M⁻¹ Rᵀ) of :meth:`_root`."""
        root = self._root()
        try:
            if root is None:
                return -float(np.trace(np.linalg.inv(m)))
            return -float(np.trace(root @ np.linalg.solve(m, root.T)))
        except np.linalg.LinAlgError:
            return -np.inf

    def smooth_value(self, m: np.ndarray) -> float:
        """The criterion, or for E its smooth surrogate; what line searches maximise."""
        return self.value(m)

    def log_information(self, m: np.ndarray) -> float:
        """log Φ(M), numerically (for E of the surrogate): :meth:`log_phi` in numpy."""
        return float(-np.log(-self.value(m)))

    def target(self, p: int) -> float:
        """The value of the equivalence statistic at the optimum (1; p for D)."""
        return 1.0

    def sensitivity(self, m: np.ndarray) -> tuple[np.ndarray, float]:
        """Sensitivity matrix H (p, p) and bound factor c at M (module docstring).

        ψ_i = tr(H M_i) is the directional derivative of Φ towards candidate i,
        normalised so that Σ w_i ψ_i = 1 at M = Σ w_i M_i. D: H = M⁻¹/p;
        A: M⁻²/tr M⁻¹; task: M⁻¹TᵀTM⁻¹/tr(TM⁻¹Tᵀ); c = 1. E: H is that of the
        surrogate (tr M^-k)^(-1/k), k = :data:`E_ORDER`, and c turns it into a
        bound on λ_min.
        """
        inv, root = np.linalg.inv(m), self._root()
        if root is None:
            return inv @ inv / np.trace(inv), 1.0
        c = root.T @ root
        return inv @ c @ inv / np.trace(c @ inv), 1.0

    def bound_value(self, value: float, ratio: float, n: float, p: int) -> float:
        """Upper bound on the criterion of any n-point design over the candidates.

        ``value`` is the criterion of a normalised relaxation M(w) and ``ratio``
        = c · max_i ψ_i ≥ 1 its equivalence-theorem ratio; the criterion of n·M
        is that of M over n (A and task), plus p log n (D), times n (E).
        """
        return value / n / ratio

    def efficiency(self, value: float, reference: float, p: int) -> float:
        """Φ(design) / Φ(reference) from criterion values: 1 as good as the reference."""
        return float(reference / value)

    def step(self, m: np.ndarray, m_j: np.ndarray, d_j: float) -> float:
        """Best step α ∈ [0, 1/2] from M towards candidate information M_j (a line search)."""
        from scipy.optimize import minimize_scalar  # only A, E and task search (slow import)

        res = minimize_scalar(lambda a: -self.smooth_value((1 - a) * m + a * m_j),
                              bounds=(0.0, 0.5), method="bounded", options={"xatol": 1e-4})
        return float(res.x)

    def prune(self, psi: np.ndarray, gap: float, p: int) -> np.ndarray | None:
        """Mask of candidates that may still carry weight (None: no rule, keep all)."""
        return None

    def added_values(self, m: np.ndarray, blocks: np.ndarray) -> np.ndarray:
        """Criterion of M + B_jᵀB_j for every block B_j (K, r, p), by rank-r updates; (K,).

        Woodbury, with U = B M⁻¹ and S = I + U Bᵀ:
        tr(C (M + BᵀB)⁻¹) = tr(C M⁻¹) − tr(S⁻¹ U C Uᵀ).
        """
        k, r, _ = blocks.shape
        inv = np.linalg.inv(m)
        u = blocks @ inv                                   # (K, r, p)
        s = np.eye(r) + np.einsum("kri,ksi->krs", u, blocks)
        root = self._root()
        base = np.trace(inv) if root is None else np.trace(root @ inv @ root.T)
        v = u if root is None else u @ root.T
        vv = np.einsum("kri,ksi->krs", v, v)
        return -(base - np.trace(np.linalg.solve(s, vv), axis1=1, axis2=2))

    def adding(self, m: np.ndarray):
        """``values(blocks)``: :meth:`added_values` at this M for blocks (K, r, p) of any K,
        what depends on M alone computed once (an exchange asks in batches at one M)."""
        return partial(self.added_values, m)

    def _root(self) -> np.ndarray | None:
        """R of the weight C = RᵀR of the trace criteria (None: identity)."""
        return None

    def cvxpy_value(self, m):
        """The criterion of a cvxpy affine matrix expression M (p, p), concave."""
        raise NotImplementedError

    def reference(self, m: np.ndarray) -> float:
        """A scale for :meth:`log_phi` at M (λ_min for E, whose powers need it; else 1)."""
        return 1.0

    def log_phi(self, m: ca.SX, reference: float = 1.0) -> ca.SX:
        """log Φ(M) as a CasADi expression of the symmetric positive-definite M (p, p)."""
        r_inv = ca.solve(ca.chol(m), ca.SX.eye(m.shape[0]))  # M⁻¹ = R⁻¹R⁻ᵀ, RᵀR = M
        root = self._root()
        return -ca.log(ca.sumsqr(r_inv if root is None else ca.DM(root) @ r_inv))


@dataclass(frozen=True, eq=False)
class DOptimal(Criterion):
    """D: log det M, the volume of the confidence ellipsoid (scale-invariant)."""

    name: ClassVar[str] = "D"
    words: ClassVar[str] = "the smallest confidence ellipsoid (log det M)"
    statistic: ClassVar[str] = "max_i tr(M⁻¹ M_i)"
    power: ClassVar[float] = 1.0

    def value(self, m):
        return log_det(m)

    def log_information(self, m):
        return self.value(m) / m.shape[0]

    def target(self, p):
        return float(p)

    def sensitivity(self, m):
        return np.linalg.inv(m) / m.shape[0], 1.0

    def bound_value(self, value, ratio, n, p):
        return value + p * np.log(n) + p * np.log(ratio)

    def efficiency(self, value, reference, p):
        return float(np.exp((value - reference) / p))

    def step(self, m, m_j, d_j):
        p = m.shape[0]
        return (d_j - p) / (p * (d_j - 1.0))

    def prune(self, psi, gap, p):
        """Harman–Pronzato: a candidate with d_i below the threshold is in no D-optimal design."""
        g = p * gap
        return p * psi >= p * (1 + g / 2 - np.sqrt(g * (4 + g - 4 / p)) / 2)

    def added_values(self, m, blocks):
        """log det(M + BᵀB) = log det M + log det(I + B M⁻¹ Bᵀ)."""
        return self.adding(m)(blocks)

    def adding(self, m):
        """:meth:`added_values` at M, with M's Cholesky factor L, L⁻¹ and log det M once."""
        inv = np.linalg.inv(np.linalg.cholesky(m))                               # L⁻¹
        base = np.linalg.slogdet(m)[1]

        def values(blocks):
            x = np.matmul(blocks, inv.T)                                         # B L⁻ᵀ
            g = np.matmul(x, x.transpose(0, 2, 1)) + np.eye(blocks.shape[1])     # I + B M⁻¹ Bᵀ
            return base + np.linalg.slogdet(g)[1]
        return values

    def cvxpy_value(self, m):
        import cvxpy as cp
        return cp.log_det(m)

    def log_phi(self, m, reference=1.0):
        return 2.0 * ca.sum1(ca.log(ca.diag(ca.chol(m)))) / m.shape[0]


@dataclass(frozen=True, eq=False)
class AOptimal(Criterion):
    """A: −tr M⁻¹, minus the sum of the (scaled) parameter variances."""

    name: ClassVar[str] = "A"
    words: ClassVar[str] = "the smallest sum of (scaled) parameter variances (−tr M⁻¹)"
    statistic: ClassVar[str] = "max_i tr(M⁻² M_i) / tr(M⁻¹)"

    def cvxpy_value(self, m):
        import cvxpy as cp
        return -cp.tr_inv(m)


@dataclass(frozen=True, eq=False)
class EOptimal(Criterion):
    """E: λ_min(M), the worst-determined direction; smooth surrogate (tr M^-k)^(-1/k)."""

    name: ClassVar[str] = "E"
    words: ClassVar[str] = "the best worst-determined direction (λ_min M)"
    statistic: ClassVar[str] = "max_i tr(G M_i) / λ_min(M), G = M^-(k+1) / tr M^-(k+1)"
    power: ClassVar[float] = 1.0 / (E_ORDER + 1)

    def value(self, m):
        return float(np.linalg.eigvalsh(m)[0])

    def smooth_value(self, m):
        """log (tr M^-k)^(-1/k), k = :data:`E_ORDER` (−inf unless M is positive definite)."""
        ev = np.linalg.eigvalsh(m)
        if ev[0] <= 0:
            return -np.inf
        return float(np.log(ev[0]) - np.log(np.sum((ev[0] / ev) ** E_ORDER)) / E_ORDER)

    def log_information(self, m):
        return self.smooth_value(m)

    def sensitivity(self, m):
        """H of the surrogate; c turns its bound into one on λ_min."""
        ev, vec = np.linalg.eigh(m)
        rel = (ev[0] / ev) ** (E_ORDER + 1)  # eigenvalue weights of M^-(k+1), scaled
        h = (vec * rel) @ vec.T / np.sum(rel * ev)
        return h, float(np.sum(rel * ev) / (ev[0] * rel.sum()))

    def bound_value(self, value, ratio, n, p):
        return value * n * ratio

    def efficiency(self, value, reference, p):
        return float(value / reference)

    def added_values(self, m, blocks):
        """λ_min of every sum (batched eigenvalues)."""
        return np.linalg.eigvalsh(m + np.einsum("kri,krj->kij", blocks, blocks))[:, 0]

    def cvxpy_value(self, m):
        import cvxpy as cp
        return cp.lambda_min(m)

    def reference(self, m):
        return float(np.linalg.eigvalsh(m)[0])

    def log_phi(self, m, reference=1.0):
        """−(1/k) log tr M^-k, computed on M / ``reference`` (about λ_min keeps powers near 1)."""
        r_inv = ca.solve(ca.chol(m), ca.SX.eye(m.shape[0]))
        x = reference * (r_inv @ r_inv.T)
        for _ in range(int(np.log2(E_ORDER))):
            x = x @ x
        return np.log(reference) - ca.log(ca.trace(x)) / E_ORDER


@dataclass(frozen=True, eq=False)
class TaskOptimal(Criterion):
    """Task: −tr(T M⁻¹ Tᵀ), minus the predicted position variance at the task poses.

    Attributes
    ----------
    task : ndarray, shape (rows, p)
        The Jacobians of the task points (TCP at task poses under task loads)
        with respect to the scaled free parameters, per unit σ (m).
    """

    task: np.ndarray
    name: ClassVar[str] = "task"
    words: ClassVar[str] = "the smallest predicted position variance at the task poses"
    statistic: ClassVar[str] = "max_i tr(M⁻¹TᵀTM⁻¹ M_i) / tr(T M⁻¹ Tᵀ)"

    def __post_init__(self):
        if np.ndim(self.task) != 2:
            raise ValueError(f"the task matrix must be 2-D (rows, parameters), got shape "
                             f"{np.shape(self.task)}")

    def _root(self):
        return self.task

    def cvxpy_value(self, m):
        import cvxpy as cp
        return -cp.matrix_frac(self.task.T, m)


def criterion(name="D", task: np.ndarray | None = None) -> Criterion:
    """The criterion object for a name of :data:`CRITERIA` (:meth:`Criterion.from_name`)."""
    return Criterion.from_name(name, task)


def check(name, task) -> None:
    """Raise ValueError for an unknown criterion name, or ``"task"`` when ``task`` is None."""
    if isinstance(name, Criterion):
        return
    if name not in CRITERIA:
        raise ValueError(f"unknown criterion {name!r}; choose one of {', '.join(CRITERIA)}")
    if name == "task" and task is None:
        raise ValueError("the task criterion needs task poses")


def efficiency(name, value: float, reference: float, p: int) -> float:
    """Φ(design) / Φ(reference) from criterion values: 1 means as good as the reference.

    D: (det M / det M_ref)^(1/p); A and task: variance_ref / variance;
    E: λ / λ_ref.
    """
    if not isinstance(name, Criterion) and name == "task":  # needs no task matrix
        name = TaskOptimal(np.zeros((0, p)))
    return Criterion.from_name(name).efficiency(value, reference, p)
