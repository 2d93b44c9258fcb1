"""The nominal robot: a frozen serial chain read from a URDF with Pinocchio.

A :class:`Robot` is what the robot *is* (joint placements, axes, limits); it
never changes. Identified corrections live in a parameter set
(:mod:`doe_calib.model.parameters`) and never write back into it.

Convention (as in Pinocchio): the pose of joint ``k`` in the robot base frame
is ``T_k = T_{k-1} · M_k · X_k(q_k)`` with ``M_k`` the constant placement of
joint ``k`` in its parent joint's frame and ``X_k`` the rotation about (or
translation along) its unit axis; the flange is ``T_f = T_N · M_f``.
"""
from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path

import numpy as np

from doe_calib.errors import ModelError

#: Pinocchio joint types a chain may hold: kind, and axis (None: the joint's own, unaligned).
_TYPES = {**{f"JointModel{r}{a}": ("revolute", a) for r in ("R", "RUB") for a in "XYZ"},
          **{f"JointModelP{a}": ("prismatic", a) for a in "XYZ"},
          "JointModelRevoluteUnaligned": ("revolute", None),
          "JointModelPrismaticUnaligned": ("prismatic", None)}
_UNBOUNDED = 1e10  # |limit| above this means "no limit" (URDF continuous joints)


@dataclass(frozen=True)
class Joint:
    """One actuated joint of the chain.

    Attributes
    ----------
    name : str
        URDF joint name.
    kind : {"revolute", "prismatic"}
    axis : tuple of 3 float
        Unit axis in the joint frame.
    placement : tuple of 16 float
        4×4 homogeneous placement in the parent joint frame (row-major, metres).
    lower, upper : float
        Limits in rad (revolute) or m (prismatic); ±inf when unbounded.
    mass : float
        Mass (kg) the joint moves as one rigid body: its link, the links fixed
        to it and any side branch (at its neutral configuration), from the
        URDF's ``<inertial>`` tags; 0 when the URDF gives none.
    com : tuple of 3 float
        Centre of that mass in the joint's frame after its motion, metres.
    velocity : float
        Maximum speed from the URDF's ``<limit velocity>``, rad/s (m/s for a
        prismatic joint); 0 when the URDF gives none.
    effort : float
        Maximum torque (N·m) or force (N) from the URDF's ``<limit effort>``;
        0 when the URDF gives none.
    """

    name: str
    kind: str
    axis: tuple
    placement: tuple
    lower: float
    upper: float
    mass: float = 0.0
    com: tuple = (0.0, 0.0, 0.0)
    velocity: float = 0.0
    effort: float = 0.0

    @property
    def placement_matrix(self) -> np.ndarray:
        """The 4×4 placement as an array (metres)."""
        return np.array(self.placement, dtype=float).reshape(4, 4)

    @property
    def display_unit(self) -> str:
        """Controller unit of this joint's position: deg or mm."""
        return "deg" if self.kind == "revolute" else "mm"

    @property
    def display_factor(self) -> float:
        """Multiply SI (rad or m) by this to get the controller unit."""
        return float(np.degrees(1.0)) if self.kind == "revolute" else 1000.0


@dataclass(frozen=True)
class Robot:
    """A frozen serial chain from the URDF root link to a flange link.

    Attributes
    ----------
    name : str
    joints : tuple of Joint
        Actuated joints from base to flange (fixed joints folded in).
    flange : str
        Name of the flange link.
    flange_placement : tuple of 16 float
        Flange frame in the last joint's frame (row-major, metres).
    source : str
        Where the description came from (URDF path), for reports.
    """

    name: str
    joints: tuple
    flange: str
    flange_placement: tuple
    source: str = ""

    def __repr__(self) -> str:
        kinds = "".join("P" if j.kind == "prismatic" else "R" for j in self.joints)
        return (f"Robot({self.name!r}, {self.n_joints} joints {kinds}: "
                f"{', '.join(self.joint_names)}; flange {self.flange!r})")

    @property
    def has_inertials(self) -> bool:
        """Whether the URDF gives the links' masses (self-weight effects need them)."""
        return any(j.mass > 0 for j in self.joints)

    @property
    def n_joints(self) -> int:
        """Number of actuated joints N."""
        return len(self.joints)

    @property
    def joint_names(self) -> list[str]:
        return [j.name for j in self.joints]

    @property
    def lower(self) -> np.ndarray:
        """Lower joint limits, shape (N,), rad or m."""
        return np.array([j.lower for j in self.joints])

    @property
    def upper(self) -> np.ndarray:
        """Upper joint limits, shape (N,), rad or m."""
        return np.array([j.upper for j in self.joints])

    @property
    def link_lengths(self) -> np.ndarray:
        """Offset of each joint frame from the one before, then of the flange, shape (N + 1,), m."""
        flange = np.array(self.flange_placement, float).reshape(4, 4)[:3, 3]
        return np.linalg.norm([*(j.placement_matrix[:3, 3] for j in self.joints), flange], axis=1)

    @property
    def display_factors(self) -> np.ndarray:
        """Per-joint factors SI → controller units (deg, mm), shape (N,)."""
        return np.array([j.display_factor for j in self.joints])

    def flange_poses(self, q) -> tuple[np.ndarray, np.ndarray]:
        """Nominal flange pose at each configuration, robot base frame (Pinocchio).

        Parameters
        ----------
        q : array_like, shape (M, N)
            Joint values, rad (m for prismatic joints).

        Returns
        -------
        rotation : ndarray, shape (M, 3, 3)
        translation : ndarray, shape (M, 3)
            Metres.
        """
        from doe_calib.model.skeleton import chain_poses

        rot, trans = [], []
        for data, flange in chain_poses(self, q):
            rot.append(data.oMf[flange].rotation.copy())
            trans.append(data.oMf[flange].translation.copy())
        return np.array(rot), np.array(trans)

    def to_dict(self) -> dict:
        """Plain JSON-able description (SI units)."""
        return {"name": self.name, "flange": self.flange, "source": self.source,
                "flange_placement": list(self.flange_placement),
                "joints": [{"name": j.name, "kind": j.kind, "axis": list(j.axis),
                            "placement": list(j.placement),
                            "lower": _finite_or_none(j.lower), "upper": _finite_or_none(j.upper),
                            "mass": j.mass, "com": list(j.com), "velocity": j.velocity,
                            "effort": j.effort}
                           for j in self.joints]}

    @classmethod
    def from_dict(cls, d: dict) -> "Robot":
        """Inverse of :meth:`to_dict`."""
        joints = tuple(Joint(j["name"], j["kind"], tuple(j["axis"]), tuple(j["placement"]),
                             -np.inf if j["lower"] is None else j["lower"],
                             np.inf if j["upper"] is None else j["upper"],
                             j.get("mass", 0.0), tuple(j.get("com", (0.0, 0.0, 0.0))),
                             j.get("velocity", 0.0), j.get("effort", 0.0))
                       for j in d["joints"])
        return cls(d["name"], joints, d["flange"], tuple(d["flange_placement"]),
                   d.get("source", ""))

    @classmethod
    def from_urdf(cls, path, flange: str | None = None) -> "Robot":
        """Read the chain from the URDF root to ``flange`` with Pinocchio.

        Parameters
        ----------
        path : path-like
            URDF file (metres, radians).
        flange : str, optional
            Flange link name; default: the last link of the chain when the
            URDF is a single chain.

        Examples
        --------
        >>> from doe_calib import examples
        >>> Robot.from_urdf(examples.ROBOT_URDF).n_joints
        6
        """
        path = Path(path)
        if not path.is_file():
            raise ModelError(f"robot file {path} does not exist")
        import pinocchio as pin

        try:
            model = pin.buildModelFromUrdf(str(path))
        except Exception as exc:  # Pinocchio raises plain RuntimeError/ValueError
            raise ModelError(f"{path}: Pinocchio cannot read this URDF: {exc}") from exc
        frame_id = _flange_frame(model, flange, path)
        frame = model.frames[frame_id]
        chain = []
        jid = frame.parentJoint
        while jid > 0:
            chain.append(jid)
            jid = model.parents[jid]
        chain.reverse()
        if not chain:
            raise ModelError(f"{path}: no actuated joint between the root and link {frame.name!r}")
        _refuse_mimic(path, [model.names[j] for j in chain])
        bodies = _rigid_bodies(model, chain)
        joints = tuple(_joint_from_model(model, j, path, bodies[j]) for j in chain)
        return cls(model.name, joints, frame.name,
                   tuple(frame.placement.homogeneous.ravel()), str(path))


def _refuse_mimic(path, chain_joints) -> None:
    """Raise a ModelError naming the first chain joint that ``<mimic>``s another."""
    import xml.etree.ElementTree as ET

    try:
        root = ET.parse(path).getroot()
    except ET.ParseError:
        return  # Pinocchio read it; nothing more to check here
    mimic = [j.get("name") for j in root.iter("joint") if j.find("mimic") is not None]
    for name in chain_joints:
        if name in mimic:
            raise ModelError(f"{path}: joint {name!r} is a <mimic> joint (it copies another "
                             f"joint); mimic joints are not supported in the chain: make it a "
                             f"fixed joint or an independent one")


def _finite_or_none(x: float):
    return None if not np.isfinite(x) else float(x)


def _flange_frame(model, flange, path) -> int:
    import pinocchio as pin

    bodies = [i for i, f in enumerate(model.frames) if f.type == pin.FrameType.BODY]
    if flange is not None:
        named = [i for i in bodies if model.frames[i].name == flange]
        if named:
            return named[0]
        names = ", ".join(model.frames[i].name for i in bodies)
        raise ModelError(f"{path}: no link named {flange!r}; links are: {names}")
    # Default: the deepest link, provided the actuated joints form one chain (no joint is the
    # parent of two).
    parents = list(model.parents)[1:]
    if len(set(parents)) < len(parents):
        raise ModelError(f"{path}: the robot is a tree, not a single chain; name the flange link "
                         f"(--flange LINK)")
    # Frames are stored in URDF traversal order: the last body on the last joint is the tip.
    return max(bodies, key=lambda i: (model.frames[i].parentJoint, i))


def _rigid_bodies(model, chain) -> dict:
    """Per chain joint, the Pinocchio inertia it moves rigidly (side branches at neutral)."""
    import pinocchio as pin

    data = model.createData()
    pin.forwardKinematics(model, data, pin.neutral(model))
    inside = set(chain)
    out = {j: pin.Inertia.Zero() for j in chain}
    for j in range(1, model.njoints):
        a = j
        while a > 0 and a not in inside:
            a = model.parents[a]
        if a in inside:
            out[a] = out[a] + (data.oMi[a].actInv(data.oMi[j])).act(model.inertias[j])
    return out


def _joint_from_model(model, jid: int, path, body) -> Joint:
    jm = model.joints[jid]
    short = jm.shortname()
    name = model.names[jid]
    if short not in _TYPES:
        raise ModelError(f"{path}: joint {name!r} is of type {short}; only revolute and prismatic "
                         f"joints are supported")
    kind, axis = _TYPES[short]
    axis = np.eye(3)["XYZ".index(axis)] if axis else np.asarray(jm.extract().axis, float)
    lo, hi, speed, effort = -np.inf, np.inf, 0.0, 0.0
    if jm.nq == 1:
        lo = float(model.lowerPositionLimit[jm.idx_q])
        hi = float(model.upperPositionLimit[jm.idx_q])
        lo = -np.inf if abs(lo) > _UNBOUNDED else lo
        hi = np.inf if abs(hi) > _UNBOUNDED else hi
        speed, effort = (float(v) if 0 < v < _UNBOUNDED else 0.0
                         for v in (model.velocityLimit[jm.idx_v], model.effortLimit[jm.idx_v]))
    placement = tuple(model.jointPlacements[jid].homogeneous.ravel())
    return Joint(name, kind, tuple(float(a) for a in axis), placement, lo, hi,
                 float(body.mass), tuple(float(c) for c in body.lever), speed, effort)
