"""The design problem in numbers: per-candidate information blocks of the free parameters."""
from __future__ import annotations

import mmap
from dataclasses import dataclass
from math import ceil

import numpy as np

from doe_calib.design.batch import map_poses
from doe_calib.design.solvers.relaxation import packed_information, packed_size
from doe_calib.design.solvers.symbolic import pose_blocks
from doe_calib.errors import OptionError
from doe_calib.estimation.identifiability import analyse
from doe_calib.io.measurements import Configurations
from doe_calib.model.evaluation import evaluate, observation_matrix
from doe_calib.model.loads import hanging_mass_wrench
from doe_calib.runtime.forked import forked_map
from doe_calib.runtime.parallel import default_workers

#: Fewest candidate poses per forked share of :func:`candidate_information`.
_SHARE = 2000


@dataclass(frozen=True)
class LoadCase:
    """A mass hung on the flange: kg, centre of mass in the flange frame (m).

    ``radius`` (m) is the sphere it is drawn as in the collision check; None:
    a steel sphere of that mass (:func:`doe_calib.collision.shapes.load_radius`).
    """

    mass: float
    com: tuple
    radius: float | None = None

    def spec(self) -> str:
        """``KG@X,Y,Z`` (mm), with ``:R`` (mm) when a radius is given, as ``--load`` reads it."""
        size = "" if self.radius is None else f":{1000 * self.radius:g}"
        return f"{self.mass:g}@" + ",".join(f"{1000 * c:g}" for c in self.com) + size


def load_configurations(model, values, q, loads, names=None) -> Configurations:
    """Each pose unloaded, then under each load case: (len(loads) + 1)·M configurations.

    Poses are named ``names`` (M ids), default 1..M."""
    q = np.atleast_2d(q)
    m, n_cases = q.shape[0], len(loads) + 1
    w = np.zeros((m, n_cases, 6))
    for c, load in enumerate(loads, start=1):
        w[:, c] = hanging_mass_wrench(model, values, q, load.mass, load.com)
    names = [str(i + 1) for i in range(m)] if names is None else [str(n) for n in names]
    pose = np.repeat(names, n_cases)
    return Configurations.from_arrays(np.repeat(q, n_cases, axis=0), w.reshape(-1, 6), pose=pose)


def blocks_for(model, params, q, loads, sigma: float) -> np.ndarray:
    """Scaled, σ-weighted observation blocks of the free parameters, shape (K, r, F).

    ``r = (len(loads) + 1) · 3n`` rows per pose (each pose unloaded, then
    under each load case, as :func:`load_configurations`); columns are
    ``∂x/∂p_i · scale_i / σ`` (``sigma`` in m). One Function of the pose
    gives them all, the wrenches included (:func:`.symbolic.pose_blocks`),
    evaluated in chunks of :data:`.batch.CHUNK` poses.
    """
    q = np.atleast_2d(np.asarray(q, float))
    if not params.free.any():
        return np.zeros((len(q), (len(loads) + 1) * 3 * model.tool.n_markers, 0))
    (blocks,) = map_poses(pose_blocks(model, params, loads, sigma), q)
    return blocks


def candidate_information(model, params, q, loads, sigma: float, spare: int = 0,
                          workers: int | None = None) -> tuple:
    """The candidates' blocks and information, computed in forked shares of the poses.

    The blocks are :func:`blocks_for`'s, shape (K, r, F); their information
    is :func:`.relaxation.packed_information`, held in the first K rows of an
    array of shape (K + ``spare``, F(F+1)/2) (the spare rows free for more
    candidates). Shares of at least :data:`_SHARE` poses are computed by
    ``workers`` forked processes (:func:`~doe_calib.runtime.forked.forked_map`;
    None: one per CPU) into memory this process shares with them; each pose's
    numbers are its own, so they do not depend on the shares.

    Returns
    -------
    (ndarray, ndarray)
        The blocks and the packed information with its spare rows.
    """
    q = np.atleast_2d(np.asarray(q, float))
    k, shares = len(q), max(1, min(default_workers() if workers is None else workers,
                                   len(q) // _SHARE))
    if shares == 1 or not params.free.any():
        blocks = blocks_for(model, params, q, loads, sigma)
        room = np.empty((k + spare, packed_size(blocks.shape[2])))
        packed_information(blocks, out=room[:k])
        return blocks, room
    function = pose_blocks(model, params, loads, sigma)
    blocks = _shared_empty((k, *function.size_out(0)))
    room = _shared_empty((k + spare, packed_size(blocks.shape[2])))
    edges = np.linspace(0, k, shares + 1).astype(int)
    forked_map(_information_share, (function, q, edges, blocks, room), shares, shares)
    return blocks, room


def _information_share(shared, i: int) -> None:
    """Share i of :func:`candidate_information`, written into its arrays."""
    function, q, edges, blocks, room = shared
    share = slice(edges[i], edges[i + 1])
    (blocks[share],) = map_poses(function, q[share])
    packed_information(blocks[share], out=room[share])


def _shared_empty(shape: tuple) -> np.ndarray:
    """An array of ``shape`` in memory shared with the processes this one forks: their writes
    are seen here."""
    return np.frombuffer(mmap.mmap(-1, max(8 * int(np.prod(shape)), 1)),
                         dtype=float).reshape(shape)


def task_matrix(model, params, configurations, point=(0.0, 0.0, 0.0)) -> np.ndarray:
    """T: Jacobian of a flange point at the task configurations w.r.t. the scaled free parameters.

    Rows are x, y, z (m, robot base frame) of ``point`` (flange frame, m) at
    each task configuration under its wrench; shape (3M, F). The predicted
    position covariance of a design with scaled information M is T M⁻¹ Tᵀ (m²).
    """
    _, jac = evaluate(model.point_robot, configurations, params.values, np.asarray(point, float))
    return (jac[..., params.free] * params.scales[params.free]).reshape(-1, int(params.free.sum()))


def design_parameters(model, params, q, loads, sample: int = 400, rng=None):
    """The parameter set with what no candidate pose can identify fixed (with reasons)."""
    rng = np.random.default_rng(0) if rng is None else rng
    q = np.atleast_2d(q)
    pick = rng.choice(len(q), size=min(sample, len(q)), replace=False)
    cfg = load_configurations(model, params.values, q[pick], loads)
    _, b = observation_matrix(model, params.values, cfg)
    return fixed_unidentifiable(params, b.reshape(-1, b.shape[-1]), "the candidate poses")


def fixed_unidentifiable(params, rows: np.ndarray, over: str):
    """``params`` with every parameter the observation ``rows`` (n, P) cannot identify fixed,
    its reason saying what the rows are ``over``."""
    for name, why in analyse(rows, params).dependent:
        params = params.fixed([name], f"{why} (over {over})")
    return params


def poses_needed(blocks, rng=None) -> int | None:
    """Fewest poses that identify every free parameter, or None if no candidates do.

    Stacks the blocks of random candidates (shape (K, r, F), as from
    :func:`blocks_for`) one pose at a time from the counting bound
    ``ceil(F / r)`` on, until their F columns have full rank: random poses
    are generic, so this is the fewest any design can use.
    """
    rng = np.random.default_rng(0) if rng is None else rng
    k_all, rows, f = blocks.shape
    norms = np.sqrt(np.einsum("kri,kri->i", blocks, blocks))
    scale = np.where(norms > 0, norms, 1.0)
    order = rng.permutation(k_all)
    for k in range(max(1, ceil(f / rows)), k_all + 1):  # unit columns, of the k poses only
        if np.linalg.matrix_rank(blocks[order[:k]].reshape(-1, f) / scale) == f:
            return k
    return None


def check_enough_poses(n_poses: int, blocks, n_markers: int, n_loads: int, rng=None) -> None:
    """Refuse fewer poses than the free (identifiable) parameters need.

    Each pose gives 3 coordinates of each of ``n_markers`` markers in each of
    its ``n_loads + 1`` load cases, so F parameters need at least
    ``ceil(F / (3 · n_markers · (n_loads + 1)))`` poses by counting; the
    fewest that really separate them (:func:`poses_needed`) may be more.

    Raises
    ------
    OptionError
        Stating both numbers and how they are found.
    """
    f = blocks.shape[2]
    per_pose = 3 * n_markers * (n_loads + 1)
    counted = max(1, ceil(f / per_pose))
    needed = poses_needed(blocks, rng)
    if needed is not None and n_poses >= needed:
        return
    why = (f"the model has {f} identifiable parameters and each pose gives {per_pose} "
           f"coordinates (3 × {n_markers} markers × {n_loads + 1} load case(s)), so at least "
           f"{counted} poses are needed by counting ({f} / {per_pose}, rounded up)")
    if needed is None:
        raise OptionError(f"{n_poses} poses (--poses): {why}, and not even all the candidate "
                          f"poses together separate every parameter")
    extra = "" if needed == counted else (f", and {needed} random poses are the fewest that "
                                          f"separate them all")
    raise OptionError(f"{n_poses} poses (--poses) are too few: {why}{extra}; ask for "
                      f"{needed} or more (more give a better design)")
