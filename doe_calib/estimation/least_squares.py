"""Levenberg–Marquardt for a Jacobian too tall to hold: it arrives in row blocks.

scipy's ``least_squares`` needs the whole Jacobian (3K × P) in memory, copied
by MINPACK; for 100 000 readings that is gigabytes. Here the caller streams
row blocks ``[J_b | r_b]`` and :func:`reduce_blocks` keeps only their QR
factor: ``[J | r] = Q [[R, z], [0, ρ]]``, so ``‖r + Jδ‖² = ‖Rδ + z‖² + ρ²``.
Every Levenberg–Marquardt step is then a P × P problem, solved by QR (never
the normal equations, whose condition number is the square of J's), and
memory stays at one block.

The damping is Marquardt's, relative to each column's norm (the largest seen,
as MINPACK keeps it), updated as Nielsen (1999) in Madsen, Nielsen &
Tingleff, *Methods for non-linear least squares problems* (2004), §3.2; the
stopping tests are MINPACK's (relative cost reduction, relative step,
gradient cosine).
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np


@dataclass(frozen=True)
class Reduction:
    """QR factor of a stacked least-squares problem ``min ‖r + Jδ‖``.

    Attributes
    ----------
    r_factor : ndarray, shape (k, P), k ≤ P
        Upper-triangular R with ``RᵀR = JᵀJ``.
    z : ndarray, shape (k,)
        ``Qᵀr``.
    norm2 : float
        ``‖r‖²`` (``‖z‖² + ρ²``).
    """

    r_factor: np.ndarray
    z: np.ndarray
    norm2: float


def reduce_blocks(blocks, n_columns: int) -> Reduction:
    """Stream row blocks ``(J_b, r_b)`` into the QR factor of the stacked problem.

    Parameters
    ----------
    blocks : iterable of (ndarray (rows, P), ndarray (rows,))
    n_columns : int
        P.

    Examples
    --------
    >>> rng = np.random.default_rng(0)
    >>> J, r = rng.normal(size=(100, 3)), rng.normal(size=100)
    >>> red = reduce_blocks([(J[:60], r[:60]), (J[60:], r[60:])], 3)
    >>> bool(np.allclose(red.r_factor.T @ red.r_factor, J.T @ J))
    True
    >>> bool(np.isclose(red.norm2, r @ r))
    True
    """
    return reduce_augmented((np.column_stack([jac, res]) for jac, res in blocks), n_columns)


def reduce_augmented(blocks, n_columns: int) -> Reduction:
    """:func:`reduce_blocks` of blocks given augmented, ``[J_b | r_b]`` (rows, P + 1).

    Each block is factored tile by tile (:func:`triangular_factor`); a caller that
    fills ``[J_b | r_b]`` in place saves the copy :func:`reduce_blocks` makes.
    """
    acc = np.zeros((0, n_columns + 1))
    for aug in blocks:
        acc = triangular_factor(aug, acc)
    k = min(acc.shape[0], n_columns)
    norm2 = float(np.sum(acc[:, -1] ** 2))
    return Reduction(acc[:k, :n_columns], acc[:k, -1], norm2)


#: Rows of one tile of :func:`triangular_factor`: a tile of a few dozen columns stays in
#: the processor's cache while it is factored.
TILE_ROWS = 512


def triangular_factor(a, above=None) -> np.ndarray:
    """R of ``[above; a]`` (``QR = [above; a]``), shape (min(rows, n), n).

    A tall matrix is factored as a tree (TSQR: Demmel et al., *Communication-optimal
    parallel and sequential QR and LU factorizations*, SIAM J. Sci. Comput. 34, 2012):
    its tiles of :data:`TILE_ROWS` rows in one batched LAPACK call, then their stacked
    R factors with the rows left over. Householder QR throughout (backward stable, as
    one QR of the whole); R is the same up to the sign of each row and rounding.

    Examples
    --------
    >>> a = np.random.default_rng(1).normal(size=(2000, 4))
    >>> r = triangular_factor(a)
    >>> r.shape, bool(np.allclose(r.T @ r, a.T @ a))
    ((4, 4), True)
    """
    a = np.asarray(a, float)
    n = a.shape[1]
    above = np.zeros((0, n)) if above is None else above
    tiles = a.shape[0] // TILE_ROWS if TILE_ROWS > n else 0
    if tiles > 1:
        whole = tiles * TILE_ROWS
        tops = np.linalg.qr(a[:whole].reshape(tiles, TILE_ROWS, n), mode="r")
        a = np.concatenate([tops.reshape(-1, n), a[whole:]])
    return np.linalg.qr(np.concatenate([above, a]), mode="r")


def restrict(reduction: Reduction, columns, scale) -> Reduction:
    """The reduction of ``[J[:, columns]·diag(scale) | r]`` from that of ``[J | r]``.

    ``[J | r] = Q [[R, z], [0, ρ]]``, so the selected, scaled problem is ``Q`` times
    ``[[R[:, columns]·diag(scale), z], [0, ρ]]``, whose own QR factor is a small one.
    """
    r_factor, z = reduction.r_factor, reduction.z
    rho = np.sqrt(max(reduction.norm2 - float(z @ z), 0.0))
    cols = r_factor[:, columns] * np.asarray(scale, float)
    rows = np.vstack([cols, np.zeros((1, cols.shape[1]))])
    return reduce_blocks([(rows, np.append(z, rho))], cols.shape[1])


@dataclass(frozen=True)
class Solution:
    """Where :func:`levenberg_marquardt` stopped.

    Attributes
    ----------
    x : ndarray, shape (P,)
    norm2 : float
        ``‖r(x)‖²``.
    reduction : Reduction
        Of the scaled Jacobian ``J(x)·diag(scale)`` at ``x``.
    iterations, evaluations : int
        Jacobian passes and residual passes.
    status : int
        1 gradient, 2 cost reduction, 3 step size (converged); 0 out of iterations.
    message : str
    """

    x: np.ndarray
    norm2: float
    reduction: Reduction
    iterations: int
    evaluations: int
    status: int
    message: str

    @property
    def converged(self) -> bool:
        return self.status > 0


def levenberg_marquardt(norm2, reduce, x0, scale, ftol: float = 1e-12, xtol: float = 1e-12,
                        gtol: float = 1e-12, max_iterations: int = 200,
                        progress=None, first: Reduction | None = None) -> Solution:
    """Minimise ``‖r(x)‖²`` given its value and the QR factor of its Jacobian.

    Parameters
    ----------
    norm2 : callable(x) -> float
        ``‖r(x)‖²``.
    reduce : callable(x) -> Reduction
        Of ``[J(x)·diag(scale) | r(x)]`` (see :func:`reduce_blocks`).
    x0, scale : ndarray, shape (P,)
        Start, and the typical size of each unknown (positive, its unit).
    ftol, xtol, gtol : float
        Stop when an accepted step lowers the cost by less than ``ftol`` of
        it (relative, actual and predicted), when the scaled step is below
        ``xtol`` of the scaled ``x``, or when every column of J is within
        ``gtol`` of orthogonal to r (cosine).
    max_iterations : int
        Jacobian passes allowed; residual passes are limited to 10× that.
    progress : callable(done, total, note), optional
        Told of every Jacobian pass: ``progress(iteration, max_iterations, note)``,
        the note ``‖r‖²`` (:mod:`doe_calib.runtime.progress`).
    first : Reduction, optional
        ``reduce(x0)`` when the caller has it already (saves one pass over the data).
    """
    x = np.asarray(x0, float).copy()
    scale = np.asarray(scale, float)
    red = reduce(x) if first is None else first
    f = red.norm2
    damping = _column_norms(red)  # Marquardt's scaling: λ acts relative to each column
    lam = 1e-3
    nu, iterations, evaluations = 2.0, 1, 1
    status, message = 0, "the iteration limit was reached before convergence"
    while iterations <= max_iterations and evaluations <= 10 * max_iterations:
        if progress is not None:
            progress(iterations, max_iterations, f"Levenberg–Marquardt, ‖r‖² {f:.4g}")
        if _gradient_cosine(red) <= gtol:
            status, message = 1, "the gradient is orthogonal to the residual (gtol)"
            break
        if red.z @ red.z <= ftol * f:  # even the Gauss–Newton step would gain less
            status, message = 2, "no step can lower the cost by more than ftol (relative)"
            break
        p = len(damping)
        step = np.linalg.lstsq(np.vstack([red.r_factor, np.sqrt(lam) * np.diag(damping)]),
                               -np.concatenate([red.z, np.zeros(p)]), rcond=None)[0]
        predicted = float(red.z @ red.z - np.sum((red.r_factor @ step + red.z) ** 2))
        if np.linalg.norm(step) <= xtol * (xtol + np.linalg.norm(x / scale)):
            status, message = 3, "the step is below the relative tolerance (xtol)"
            break
        x_new = x + scale * step
        f_new = norm2(x_new)
        evaluations += 1
        rho = (f - f_new) / predicted if np.isfinite(f_new) and predicted > 0 else -1.0
        if rho > 0:
            small = f - f_new <= ftol * f
            x, f = x_new, f_new
            lam *= max(1.0 / 3.0, 1.0 - (2.0 * rho - 1.0) ** 3)
            nu = 2.0
            red = reduce(x)
            damping = np.maximum(damping, _column_norms(red))
            iterations += 1
            if small:
                status, message = 2, "the cost fell by less than ftol (relative)"
                break
        else:
            lam *= nu
            nu *= 2.0
    return Solution(x, f, red, iterations, evaluations, status, message)


def _column_norms(red: Reduction) -> np.ndarray:
    """‖J_i‖ of each column (those of R), 1 for a column that is all zero."""
    cols = np.linalg.norm(red.r_factor, axis=0)
    return np.where(cols > 0, cols, 1.0)


def _gradient_cosine(red: Reduction) -> float:
    """max_i |J_iᵀ r| / (‖J_i‖ ‖r‖): MINPACK's gtol measure."""
    rnorm = np.sqrt(red.norm2)
    if rnorm == 0.0:
        return 0.0
    cols = np.linalg.norm(red.r_factor, axis=0)
    g = red.r_factor.T @ red.z
    return float(np.max(np.abs(g) / np.where(cols > 0, cols, np.inf) / rnorm, initial=0.0))
