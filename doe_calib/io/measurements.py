"""Plain containers for what is measured: configurations and marker readings.

Everything here is in SI units (m, rad, N, N·m); conversion to the files'
units (mm, deg) happens in :mod:`doe_calib.io.csv_files`.
"""
from __future__ import annotations

from dataclasses import dataclass, replace

import numpy as np

#: The environment fields every robot has, in the order they open the model's
#: ``env`` input: temperature in °C (NaN when not measured). The full vector,
#: with one approach direction per joint, is :func:`env_fields`.
ENV_FIELDS = ("temperature",)

#: Where the readings' σ comes from (the policy is :mod:`doe_calib.estimation.sigma`): an
#: option or keyword, the file's ``sigma`` column, the σ̂ of the starting model's fit, or
#: (none given) the spread of repeated readings.
GIVEN, PER_READING, ESTIMATED = "given", "per reading", "estimated"
REPEATED = "repeated readings"
SIGMA_SOURCES = (GIVEN, PER_READING, ESTIMATED, REPEATED)
#: Fewest readings of an unknown plane or ballbar pivot: 3 place it, the fourth is the first
#: that informs.
MIN_TOUCHES = 4


def env_fields(n_joints: int) -> tuple:
    """Names of the model's ``env`` input for an N-joint robot, in order.

    ``("temperature", "approach1", …, "approachN")``: the temperature (°C,
    NaN when not measured), then for each joint the direction from which it
    reached the configuration: +1 (moving up, q increasing), −1 (moving
    down), 0 (unknown). See :func:`approach_from_order`.

    Examples
    --------
    >>> env_fields(2)
    ('temperature', 'approach1', 'approach2')
    """
    return ENV_FIELDS + tuple(f"approach{k + 1}" for k in range(n_joints))


def approach_from_order(q, tol: float = 0.0) -> np.ndarray:
    """Direction from which each joint reached each configuration, visited in row order.

    Configuration i gets ``sign(q_k(i) − q_k(i−1))`` for joint k; when the
    joint did not move (``|Δq| <= tol``) it keeps the previous
    configuration's direction; the first configuration gets 0 (unknown).

    Parameters
    ----------
    q : array_like, shape (M, N)
        Joint positions in measurement order (any unit; ``tol`` in the same).
    tol : float
        Largest change that counts as "did not move".

    Returns
    -------
    ndarray, shape (M, N)
        +1, −1 or 0.

    Examples
    --------
    >>> approach_from_order([[0.0], [1.0], [1.0], [0.5]]).ravel().tolist()
    [0.0, 1.0, 1.0, -1.0]
    """
    q = np.atleast_2d(np.asarray(q, dtype=float))
    out = np.zeros_like(q)
    for i in range(1, q.shape[0]):
        step = q[i] - q[i - 1]
        out[i] = np.where(np.abs(step) > tol, np.sign(step), out[i - 1])
    return out


@dataclass(frozen=True, eq=False)
class Configurations:
    """Robot configurations with their load cases (a design, or what was measured).

    Attributes
    ----------
    pose : tuple of str, length M
        Pose id of each configuration; one pose measured under two loads gives
        two configurations with the same id and q (or q whole turns apart on a joint of more
        than a turn, as logged: :mod:`doe_calib.io.logged_turns`).
    q : ndarray, shape (M, N)
        Joint positions, rad (revolute) or m (prismatic).
    wrench : ndarray, shape (M, 6)
        Force (N) and moment (N·m) applied at the flange origin, robot base frame.
    env : ndarray, shape (M, 1 + N)
        Environment variables (see :func:`env_fields`): temperature (°C, NaN
        when not measured), then each joint's approach direction (+1, −1, 0
        unknown). An (M, 1) or (M,) temperature-only array is accepted and
        completed with approach 0.
    """

    pose: tuple
    q: np.ndarray
    wrench: np.ndarray
    env: np.ndarray

    def __post_init__(self):
        m, n = self.q.shape
        env = np.asarray(self.env, dtype=float)
        env = env.reshape(m, 1) if env.ndim == 1 else env
        if env.shape[1] == len(ENV_FIELDS):
            env = np.hstack([env, np.zeros((m, n))])
        if env.shape != (m, len(ENV_FIELDS) + n):
            raise ValueError(f"env has shape {env.shape}; expected ({m}, {len(ENV_FIELDS)}) "
                             f"(temperature) or ({m}, {len(ENV_FIELDS) + n}) "
                             f"({', '.join(env_fields(n))})")
        if not np.isin(env[:, len(ENV_FIELDS):], (-1.0, 0.0, 1.0)).all():
            raise ValueError("approach directions must be +1, -1 or 0")
        object.__setattr__(self, "env", env)

    @classmethod
    def from_arrays(cls, q, wrench=None, env=None, pose=None,
                    approach=None) -> "Configurations":
        """Build from arrays.

        Missing wrench is zero, missing env is NaN temperature and approach 0,
        ids are 1..M. ``env`` is (M, 1) temperature or the full (M, 1 + N);
        ``approach`` (M, N), when given, sets the approach directions.
        """
        q = np.atleast_2d(np.asarray(q, dtype=float))
        m, n = q.shape
        wrench = np.zeros((m, 6)) if wrench is None else np.asarray(wrench, float).reshape(m, 6)
        env = np.full((m, len(ENV_FIELDS)), np.nan) if env is None else \
            np.asarray(env, float).reshape(m, -1 if m else len(ENV_FIELDS))
        if approach is not None:
            env = np.hstack([env[:, :len(ENV_FIELDS)], np.asarray(approach, float).reshape(m, n)])
        pose = tuple(str(i + 1) for i in range(m)) if pose is None else tuple(map(str, pose))
        return cls(pose, q, wrench, env)

    @property
    def temperature(self) -> np.ndarray:
        """Temperature of each configuration, °C (NaN when not measured), shape (M,)."""
        return self.env[:, 0]

    @property
    def approach(self) -> np.ndarray:
        """Approach direction of each joint (+1, −1, 0 unknown), shape (M, N)."""
        return self.env[:, len(ENV_FIELDS):]

    def __len__(self) -> int:
        return self.q.shape[0]

    def subset(self, index) -> "Configurations":
        """The configurations at ``index`` (array of ints or booleans)."""
        index = np.asarray(index)
        if index.dtype == bool:
            index = np.flatnonzero(index)
        return Configurations(tuple(map(self.pose.__getitem__, index.tolist())), self.q[index],
                              self.wrench[index], self.env[index])


@dataclass(frozen=True, eq=False)
class Measurements:
    """Marker readings: one row per observed marker (formats.md §3), in SI.

    Attributes
    ----------
    configurations : Configurations
        The M distinct (pose, wrench, environment) configurations, in order of
        first appearance in the file (the measurement order).
    config : ndarray of int, shape (K,)
        Configuration of each reading.
    marker : ndarray of int, shape (K,)
        Marker of each reading (index into the tool's names).
    xyz : ndarray, shape (K, 3)
        Measured marker position in the measurement-device frame, metres.
    sigma : ndarray, shape (K,)
        Standard deviation of each coordinate of the reading, metres; NaN where
        none is given (:mod:`doe_calib.estimation.sigma` decides it).
    line : ndarray of int, shape (K,)
        Source line of each reading (0 when not from a file).
    source : str
        The file, for messages.
    dropped : tuple of str
        One message per input row dropped on request (``skip_bad``); never
        dropped silently.
    warnings : tuple of str
        One message per reading accepted with a doubt (a joint a hair past its
        limit), naming file, line and column; one naming the poses logged a whole turn
        apart, when some are (:mod:`doe_calib.io.logged_turns`).
    session : tuple of str
        The measurement session of each configuration (length M; empty: one
        session). Cross-validation holds out whole sessions when there are several.
    sigma_estimated : bool
        True while σ is still to be estimated: none was given (no ``sigma``
        column, no ``--sigma``); identification estimates σ from the residuals
        (formats.md §3), :func:`~doe_calib.estimation.sigma.resolve_sigma`
        settles it. True implies ``sigma_source`` ``"estimated"``.
    sigma_source : str
        Where ``sigma`` comes from (:data:`SIGMA_SOURCES`): ``"given"`` (an
        option or keyword; the default for readings built in code),
        ``"per reading"`` (the file's ``sigma`` column), ``"estimated"``
        (σ̂ of the starting model; still to come while ``sigma_estimated``) or
        ``"repeated readings"`` (none given: the spread of poses read more than once).
    observed_per_configuration : int
        Independent scalar observations behind each configuration's readings
        when they are derived from fewer numbers than 3 per reading (6 for the
        virtual points of a 6-DoF probe pose); 0: 3 per reading. Sets the
        degrees of freedom of σ̂ and χ².
    socket : ndarray of int, shape (K,), optional
        For a contact (formats.md §3, *Socket contacts*): the socket (index into
        ``socket_names``) in which the marker was seated; −1 for a tracker reading. None:
        every reading is a tracker reading. A contact's ``xyz`` is its socket's given
        position (then it counts as a reading of that point), or NaN: unknown (a
        :attr:`contact`). With a ``distance``, the socket is the pivot of a ballbar.
    socket_names : tuple of str
        The sockets' ids, in order of first appearance.
    plane : ndarray of int, shape (K,), optional
        For a plane touch (formats.md §3, *Plane touches*): the plane (index into
        ``plane_names``), its position unknown, on which the marker lay; −1 otherwise.
        None: no reading touches a plane.
    plane_names : tuple of str
        The planes' ids, in order of first appearance.
    distance : ndarray, shape (K,), optional
        For a ballbar reading (formats.md §3, *Ballbar and gauge lengths*): the length
        measured from its socket's point (the pivot) to the marker, m; NaN otherwise (a
        contact seated in its socket). None: no such reading.
    socket_sigma : ndarray, shape (K,), optional
        For a contact in a socket of given position: that position's std per axis (its
        drawing's tolerance), m, common to all the socket's contacts; 0 (exact) otherwise.
        None: 0 for every reading.
    plane_normal : ndarray, shape (K, 3), optional
        For a touch of a plane of given position (formats.md §3, *Plane touches*): the
        plane's unit normal, its ``xyz`` a point of the plane (m, the frame of the
        readings); NaN otherwise (a plane of unknown position, or no touch). None: no plane
        of given position.
    """

    configurations: Configurations
    config: np.ndarray
    marker: np.ndarray
    xyz: np.ndarray
    sigma: np.ndarray
    line: np.ndarray
    source: str = ""
    dropped: tuple = ()
    warnings: tuple = ()
    session: tuple = ()
    sigma_estimated: bool = False
    sigma_source: str = GIVEN
    observed_per_configuration: int = 0
    socket: np.ndarray | None = None
    socket_names: tuple = ()
    plane: np.ndarray | None = None
    plane_names: tuple = ()
    distance: np.ndarray | None = None
    socket_sigma: np.ndarray | None = None
    plane_normal: np.ndarray | None = None

    def __post_init__(self):
        if self.sigma_source not in SIGMA_SOURCES:
            raise ValueError(f"sigma_source must be one of {', '.join(SIGMA_SOURCES)}, got "
                             f"{self.sigma_source!r}")
        if self.sigma_estimated and self.sigma_source != ESTIMATED:  # σ to be estimated
            object.__setattr__(self, "sigma_source", ESTIMATED)

    def __len__(self) -> int:
        return self.config.shape[0]

    @property
    def n_coordinates(self) -> int:
        """Number of independent scalar observations: 3K, or 6 per pose of a 6-DoF probe."""
        if self.observed_per_configuration:
            return self.observed_per_configuration * len(np.unique(self.config))
        scalar = self.touch | self.ballbar  # one coordinate each: along the normal, the bar
        return 3 * int(np.sum(~scalar)) + int(np.sum(scalar)) - \
            3 * (len(self.sockets_used) + len(self.planes_used))

    @property
    def contact(self) -> np.ndarray:
        """Which readings have no coordinates, shape (K,) bool: contacts in a socket of
        unknown position, ballbar readings and plane touches (none without them); a contact
        in a socket whose position is given is a reading of that point."""
        return self._in(self.socket) & np.isnan(self.xyz[:, 0]) | self._in(self.plane)

    @property
    def touch(self) -> np.ndarray:
        """Which readings are plane touches, shape (K,) bool."""
        return self._in(self.plane)

    @property
    def given_plane(self) -> np.ndarray:
        """Which readings are touches of a plane of given position, shape (K,) bool."""
        return np.zeros(len(self), bool) if self.plane_normal is None else \
            self.touch & np.isfinite(self.plane_normal[:, 0])

    @property
    def ballbar(self) -> np.ndarray:
        """Which readings are ballbar lengths from their socket's point, shape (K,) bool."""
        return np.zeros(len(self), bool) if self.distance is None else \
            np.isfinite(self.distance)

    def _in(self, index) -> np.ndarray:
        return np.zeros(len(self), bool) if index is None else index >= 0

    @property
    def planes_used(self) -> np.ndarray:
        """Indices (into ``plane_names``) of the planes of unknown position some reading
        touches: each is 3 numbers the readings must also pay for (a plane of given position
        is not among them)."""
        return np.unique(self.plane[self.touch & ~self.given_plane]) \
            if self.plane is not None else np.zeros(0, int)

    @property
    def sockets_used(self) -> np.ndarray:
        """Indices (into ``socket_names``) of the sockets some reading is seated in: each
        is one unknown point, 3 coordinates the readings must also pay for."""
        return np.unique(self.socket[self._in(self.socket) & self.contact]) \
            if self.socket is not None else np.zeros(0, int)

    def subset(self, rows) -> "Measurements":
        """The readings at ``rows``, keeping only the configurations they use."""
        rows = np.asarray(rows)
        if rows.dtype == bool:
            rows = np.flatnonzero(rows)
        used, new_config = np.unique(self.config[rows], return_inverse=True)
        return Measurements(self.configurations.subset(used), new_config, self.marker[rows],
                            self.xyz[rows], self.sigma[rows], self.line[rows], self.source,
                            session=tuple(self.sessions[used]),
                            sigma_estimated=self.sigma_estimated,
                            sigma_source=self.sigma_source,
                            observed_per_configuration=self.observed_per_configuration,
                            socket=None if self.socket is None else self.socket[rows],
                            socket_names=self.socket_names,
                            plane=None if self.plane is None else self.plane[rows],
                            plane_names=self.plane_names,
                            distance=None if self.distance is None else self.distance[rows],
                            socket_sigma=None if self.socket_sigma is None
                            else self.socket_sigma[rows],
                            plane_normal=None if self.plane_normal is None
                            else self.plane_normal[rows])

    @property
    def sessions(self) -> np.ndarray:
        """Session name of each configuration, shape (M,) (the source when none was given)."""
        m = len(self.configurations)
        return np.array(self.session if self.session else (self.source,) * m, dtype=object)

    def with_approach_reversed(self) -> "Measurements":
        """The same readings with every approach direction negated (+1 ↔ −1, 0 stays).

        For files whose approach convention is the reverse of formats.md §3 (a
        controller that logs the direction the joint will leave by, rows written
        in reverse measurement order): ``backlash`` in ``approach`` mode then fits
        the band's width positive (``--approach-sign reversed`` on the command line).
        """
        cfg = self.configurations
        env = cfg.env.copy()
        env[:, len(ENV_FIELDS):] = -env[:, len(ENV_FIELDS):] + 0.0  # no -0.0
        return replace(self, configurations=Configurations(cfg.pose, cfg.q, cfg.wrench, env))

    def split_by_pose(self, held_out_poses) -> tuple["Measurements", "Measurements"]:
        """Split into (kept, held out) by pose id, for validation on unseen poses."""
        held = set(map(str, held_out_poses))
        is_held = np.array([self.configurations.pose[c] in held for c in self.config])
        return self.subset(~is_held), self.subset(is_held)


def concatenate(parts) -> Measurements:
    """Join several Measurements (e.g. sessions) into one, in the given order."""
    parts = list(parts)
    offsets = np.cumsum([0] + [len(p.configurations) for p in parts[:-1]])
    cfgs = [p.configurations for p in parts]
    configurations = Configurations(sum((c.pose for c in cfgs), ()),
                                    np.concatenate([c.q for c in cfgs]),
                                    np.concatenate([c.wrench for c in cfgs]),
                                    np.concatenate([c.env for c in cfgs]))
    return Measurements(configurations,
                        np.concatenate([p.config + o for p, o in zip(parts, offsets)]),
                        np.concatenate([p.marker for p in parts]),
                        np.concatenate([p.xyz for p in parts]),
                        np.concatenate([p.sigma for p in parts]),
                        np.concatenate([p.line for p in parts]),
                        "; ".join(dict.fromkeys(p.source for p in parts)),
                        sum((p.dropped for p in parts), ()),
                        sum((p.warnings for p in parts), ()),
                        tuple(s for p in parts for s in p.sessions),
                        any(p.sigma_estimated for p in parts), joined_sigma_source(parts),
                        _joined_observed(parts), *_joined_ids(parts, "socket"),
                        *_joined_ids(parts, "plane"),
                        None if all(p.distance is None for p in parts) else
                        np.concatenate([np.full(len(p), np.nan) if p.distance is None else
                                        p.distance for p in parts]),
                        None if all(p.socket_sigma is None for p in parts) else
                        np.concatenate([np.zeros(len(p)) if p.socket_sigma is None else
                                        p.socket_sigma for p in parts]),
                        None if all(p.plane_normal is None for p in parts) else
                        np.concatenate([np.full((len(p), 3), np.nan) if p.plane_normal is None
                                        else p.plane_normal for p in parts]))


def _joined_ids(parts, kind: str) -> tuple:
    """``(socket, socket_names)`` (``kind`` "socket") or ``(plane, plane_names)`` of joined
    parts: an id names one socket's point, or one plane, in all."""
    if all(getattr(p, kind) is None for p in parts):
        return None, ()
    names = tuple(dict.fromkeys(n for p in parts for n in getattr(p, f"{kind}_names")))
    at = {n: i for i, n in enumerate(names)}
    return np.concatenate([np.full(len(p), -1) if getattr(p, kind) is None else
                           np.array([at[getattr(p, f"{kind}_names")[i]] if i >= 0 else -1
                                     for i in getattr(p, kind).tolist()], int)
                           for p in parts]), names


def _joined_observed(parts) -> int:
    """``observed_per_configuration`` of joined parts; they must agree."""
    counts = {p.observed_per_configuration for p in parts}
    if len(counts) > 1:
        raise ValueError("cannot join marker readings with the virtual points of a 6-DoF "
                         "probe: their observation counts differ")
    return counts.pop()


def joined_sigma_source(parts) -> str:
    """The σ source of readings joined from ``parts``: estimated if any part's is, one source
    if all share it, else per reading (σ differs from reading to reading)."""
    sources = {p.sigma_source for p in parts}
    if ESTIMATED in sources:
        return ESTIMATED
    return sources.pop() if len(sources) == 1 else PER_READING


#: σ (m) a fit that estimates σ weighs readings without one by: any uniform σ gives the same
#: estimate, and σ̂ replaces it.
PROVISIONAL_SIGMA = 1e-3


def provisional(measurements: "Measurements") -> "Measurements":
    """The readings a fit that estimates σ weighs: those without σ at
    :data:`PROVISIONAL_SIGMA`, still ``sigma_estimated``."""
    missing = np.isnan(measurements.sigma)
    if not missing.any():
        return measurements
    return replace(measurements, sigma=np.where(missing, PROVISIONAL_SIGMA, measurements.sigma))
