"""Measurement campaigns simulated independently of doe_calib (numpy and Pinocchio only).

Tests use it to judge doe_calib on data its own effect modules did not
generate. SI inside (m, rad, N, N·m); the CSV it writes is formats.md §3
(mm, deg). A reading of marker j in configuration i is::

    p_ij = p_b + R_b · oMf(q_i + Δq_i + θ_i) · u_j + noise

with ``oMf`` Pinocchio's flange-frame pose on the model whose chain-joint
placements are perturbed (``M_k ← M_k · exp6(ξ_k)``), ``Δq`` the constant
joint offsets plus the angle-dependent effects, and ``θ`` the deflections.
Torques are evaluated on the nominal model at the commanded q:

* ``τ = Jᵀ F``: the applied wrench ``F = (f, m)`` at the flange origin, robot
  root axes, with ``J`` the 6×N flange Jacobian (``LOCAL_WORLD_ALIGNED``);
* ``g(q)``: ``pin.computeGeneralizedGravity``, the torque the motors supply to
  hold the arm. Its load on the joints is ``−g``, so a self-weight compliance
  ``c > 0`` deflects by ``θ = −c·g``, the same way as ``θ = c·τ`` under a payload.

Joints are numbered k = 0 … N−1 along the chain, root to flange.
"""
from __future__ import annotations

import csv
import importlib.metadata
from dataclasses import dataclass

import numpy as np
import pinocchio as pin

_KINDS = {"JointModelRX": "revolute", "JointModelRY": "revolute", "JointModelRZ": "revolute",
          "JointModelRevoluteUnaligned": "revolute", "JointModelPX": "prismatic",
          "JointModelPY": "prismatic", "JointModelPZ": "prismatic",
          "JointModelPrismaticUnaligned": "prismatic"}
WRENCH = ("fx", "fy", "fz", "mx", "my", "mz")


@dataclass(frozen=True, eq=False)
class Chain:
    """The nominal robot (Pinocchio model) and its serial chain root → flange.

    Attributes: ``model``, ``data`` (scratch), ``flange`` (frame id), ``joints``
    (Pinocchio joint ids, root first), ``idx_q``/``idx_v`` (N,), ``names``,
    ``kinds`` ("revolute"/"prismatic"), ``lower``/``upper`` (N,) limits, rad or m.
    """

    model: pin.Model
    data: pin.Data
    flange: int
    joints: tuple
    idx_q: np.ndarray
    idx_v: np.ndarray
    names: tuple
    kinds: tuple
    lower: np.ndarray
    upper: np.ndarray

    @classmethod
    def from_urdf(cls, path, flange: str) -> "Chain":
        """Read a URDF; the chain is the joints supporting the frame ``flange``.

        >>> Chain.from_urdf(ur10_urdf(), "tool0").names[0]
        'shoulder_pan_joint'
        """
        model = pin.buildModelFromUrdf(str(path))
        if not model.existFrame(flange):
            raise ValueError(f"{path}: no frame named {flange!r}")
        body = model.existFrame(flange, pin.BODY)  # a link, if a joint has the same name
        fid = model.getFrameId(flange, pin.BODY) if body else model.getFrameId(flange)
        joints = tuple(j for j in model.supports[model.frames[fid].parentJoint] if j > 0)
        shorts = [model.joints[j].shortname() for j in joints]
        if any(s not in _KINDS for s in shorts):
            raise ValueError(f"{path}: chain joints must be revolute or prismatic, got {shorts}")
        idx_q = np.array([model.joints[j].idx_q for j in joints])
        return cls(model, model.createData(), fid, joints, idx_q,
                   np.array([model.joints[j].idx_v for j in joints]),
                   tuple(model.names[j] for j in joints), tuple(_KINDS[s] for s in shorts),
                   model.lowerPositionLimit[idx_q].copy(), model.upperPositionLimit[idx_q].copy())

    def full(self, q) -> np.ndarray:
        """Pinocchio configuration (nq,): chain joints at ``q`` (N,), the rest at neutral."""
        out = pin.neutral(self.model)
        out[self.idx_q] = q
        return out

    def file_units(self) -> np.ndarray:
        """Factor SI → file unit of each joint (N,): 180/π (deg) or 1000 (mm)."""
        return np.array([np.degrees(1.0) if k == "revolute" else 1000.0 for k in self.kinds])


# --- hidden effects: delta(q, tau, g) -> (M,) added to joint `joint`; q, tau, g are (M, N) SI --
@dataclass(frozen=True)
class SmoothAngleCompliance:
    """θ = (c0 + c1·cos(q_k − phase))·τ_k; c0, c1 in rad/(N·m), phase in rad."""
    joint: int
    c0: float
    c1: float
    phase: float = 0.0

    def delta(self, q, tau, g):
        k = self.joint
        return (self.c0 + self.c1 * np.cos(q[:, k] - self.phase)) * tau[:, k]


@dataclass(frozen=True)
class TorqueSignBacklash:
    """θ = (width/2)·sign(τ_k), 0 where |τ_k| < 1e-9; width in rad (m if prismatic)."""
    joint: int
    width: float

    def delta(self, q, tau, g):
        t = tau[:, self.joint]
        return 0.5 * self.width * np.where(np.abs(t) < 1e-9, 0.0, np.sign(t))


@dataclass(frozen=True)
class ApproachBacklash:
    """θ = −(width/2)·a_k: a static joint's output lags half the band behind the motor that
    brought it there, a_k the direction joint k approached from (+1 moving up, −1 down, 0
    unknown); width in rad (m if prismatic). Needs the approach (``uses_approach``)."""
    joint: int
    width: float
    uses_approach = True

    def delta(self, q, tau, g, approach):
        return -0.5 * self.width * approach[:, self.joint]


@dataclass(frozen=True)
class CrossCoupling:
    """Δq_joint = amplitude·sin(q_source): an error driven by another joint's angle."""
    joint: int
    source: int
    amplitude: float

    def delta(self, q, tau, g):
        return self.amplitude * np.sin(q[:, self.source])


@dataclass(frozen=True)
class SelfWeightCompliance:
    """θ = −c·g_k(q), g the motors' gravity torque (module docstring); c in rad/(N·m)."""
    joint: int
    c: float

    def delta(self, q, tau, g):
        return -self.c * g[:, self.joint]


@dataclass(frozen=True)
class Cyclic:
    """Δq = amplitude·sin(harmonic·q_k + phase); amplitude in rad, phase in rad."""
    joint: int
    amplitude: float
    harmonic: int
    phase: float = 0.0

    def delta(self, q, tau, g):
        return self.amplitude * np.sin(self.harmonic * q[:, self.joint] + self.phase)


@dataclass(frozen=True, eq=False)
class Truth:
    """What the simulated robot really is.

    Attributes
    ----------
    base_rotvec, base_position : ndarray (3,)
        Root pose in the tracker frame: rotation vector (rad), position (m).
    markers : ndarray (n, 3)
        True marker positions in the flange frame, m.
    offsets : ndarray (N,)
        Joint offsets Δq (rad or m): the joint is at commanded q + Δq.
    twists : ndarray (N, 6)
        Placement errors ξ_k = (v, ω) (m, rad): ``M_k ← M_k · exp6(ξ_k)``.
    effects : tuple
        Hidden effects (the classes above).
    """

    base_rotvec: np.ndarray
    base_position: np.ndarray
    markers: np.ndarray
    offsets: np.ndarray
    twists: np.ndarray
    effects: tuple = ()

    @classmethod
    def nominal(cls, chain, markers_m, effects=()) -> "Truth":
        """Identity base, nominal geometry and markers, zero offsets."""
        n = len(chain.joints)
        return cls(np.zeros(3), np.zeros(3), np.array(markers_m, float), np.zeros(n),
                   np.zeros((n, 6)), tuple(effects))

    @classmethod
    def random(cls, chain, markers_nominal_m, rng, scale: float = 1.0, effects=()) -> "Truth":
        """A realistic truth: base 2–3 m away turned by 90–160°; offsets σ 0.05° (0.05 mm),
        placement errors σ 0.2 mm / 0.01°, marker errors σ 1 mm; all but the base × ``scale``.
        """
        n = len(chain.joints)
        axis, where = rng.normal(size=(2, 3))
        rotvec = axis / np.linalg.norm(axis) * np.radians(rng.uniform(90.0, 160.0))
        position = where / np.linalg.norm(where) * rng.uniform(2.0, 3.0)
        unit = np.where(np.array(chain.kinds) == "revolute", np.radians(1.0), 1e-3)
        offsets = scale * 0.05 * unit * rng.normal(size=n)
        twists = scale * rng.normal(size=(n, 6)) * np.r_[[0.2e-3] * 3, [np.radians(0.01)] * 3]
        markers = np.array(markers_nominal_m, float)
        markers = markers + scale * 1e-3 * rng.normal(size=markers.shape)
        return cls(rotvec, position, markers, offsets, twists, tuple(effects))

    def robot_model(self, chain) -> pin.Model:
        """A copy of the nominal model with the chain placements perturbed."""
        model = pin.Model(chain.model)
        for j, xi in zip(chain.joints, self.twists):
            model.jointPlacements[j] = model.jointPlacements[j] * pin.exp6(pin.Motion(xi))
        return model


def joint_torques(chain, q_si, wrench) -> np.ndarray:
    """τ = Jᵀ F (M, N), N·m or N, of the flange wrench (M, 6); nominal model at q (M, N)."""
    out = []
    for q, w in zip(np.atleast_2d(q_si), np.atleast_2d(wrench)):
        jac = pin.computeFrameJacobian(chain.model, chain.data, chain.full(q), chain.flange,
                                       pin.LOCAL_WORLD_ALIGNED)
        out.append(jac[:, chain.idx_v].T @ w)
    return np.array(out)


def gravity_torques(chain, q_si) -> np.ndarray:
    """g(q) (M, N): torques the motors supply to hold the nominal arm still, N·m or N."""
    return np.array([pin.computeGeneralizedGravity(chain.model, chain.data, chain.full(q))
                     [chain.idx_v] for q in np.atleast_2d(q_si)])


def marker_positions(chain, truth, q_si, wrench, approach=None) -> np.ndarray:
    """True marker positions (M, n, 3) in the tracker frame, m, for commanded q (M, N) SI and
    wrench (M, 6) N, N·m (flange origin, root axes); ``approach`` (M, N) of ±1/0, the
    direction each joint came from (0 when not given), for effects that use it."""
    q = np.atleast_2d(np.asarray(q_si, float))
    tau, g = joint_torques(chain, q, wrench), gravity_torques(chain, q)
    approach = np.zeros_like(q) if approach is None else np.asarray(approach, float)
    x = q + truth.offsets
    for e in truth.effects:
        x[:, e.joint] += (e.delta(q, tau, g, approach) if getattr(e, "uses_approach", False)
                          else e.delta(q, tau, g))
    model = truth.robot_model(chain)
    data = model.createData()
    rot = pin.exp3(np.asarray(truth.base_rotvec, float))
    out = []
    for xi in x:
        pin.framesForwardKinematics(model, data, chain.full(xi))
        om = data.oMf[chain.flange]
        out.append((truth.markers @ om.rotation.T + om.translation) @ rot.T + truth.base_position)
    return np.array(out)


def payload_wrench(chain, q_si, mass_kg: float, com_flange_m) -> np.ndarray:
    """Wrench (M, 6) of a mass hung on the flange: ``f = mass·gravity`` (the model's gravity,
    −9.81 m/s² along root z) and the moment of its centre (flange frame, m) about the
    flange origin, in root axes; flange placed on the nominal model at q (M, N)."""
    f = mass_kg * chain.model.gravity.linear
    out = []
    for q in np.atleast_2d(q_si):
        pin.framesForwardKinematics(chain.model, chain.data, chain.full(q))
        arm = chain.data.oMf[chain.flange].rotation @ np.asarray(com_flange_m, float)
        out.append(np.r_[f, np.cross(arm, f)])
    return np.array(out)


def pull_wrench(chain, q_si, mass_kg: float, com_flange_m, direction, g: float = 9.80665):
    """Wrench (M, 6) of the force ``mass·g`` along the unit ``direction`` (root axes) acting at
    the centre ``com_flange_m`` (flange frame, m): the force and its moment about the flange
    origin, root axes; flange placed on the nominal model at q (M, N)."""
    f = mass_kg * g * np.asarray(direction, float)
    out = []
    for q in np.atleast_2d(q_si):
        pin.framesForwardKinematics(chain.model, chain.data, chain.full(q))
        arm = chain.data.oMf[chain.flange].rotation @ np.asarray(com_flange_m, float)
        out.append(np.r_[f, np.cross(arm, f)])
    return np.array(out)


def unloaded_and_loaded(chain, q_si, mass_kg: float, com_flange_m):
    """Each pose twice, unloaded then with the payload: q (2M, N) and wrench (2M, 6)."""
    q = np.repeat(np.atleast_2d(q_si), 2, axis=0)
    w = np.zeros((len(q), 6))
    w[1::2] = payload_wrench(chain, q[1::2], mass_kg, com_flange_m)
    return q, w


def random_configurations(chain, m: int, rng, margin: float = 0.05, within=None) -> np.ndarray:
    """m configurations (m, N) SI, uniform inside the limits (or ``within`` (N, 2)) shrunk by
    ``margin`` × range at each end."""
    lo, hi = (chain.lower, chain.upper) if within is None else np.asarray(within, float).T
    pad = margin * (hi - lo)
    return rng.uniform(lo + pad, hi - pad, size=(m, len(lo)))


def write_campaign(path, chain, truth, q_si, wrench, marker_names, sigma_mm: float, rng,
                   outliers=(), shuffle: bool = False, write_sigma: bool = True,
                   approach=None, written_approach_sign: float = 1.0) -> dict:
    """Write a measurement CSV (formats.md §3) of every marker in every configuration.

    Configurations with identical q share a pose id ("1", "2", … by first appearance) and
    are written together, in the given order; ``shuffle`` permutes the poses.

    Parameters
    ----------
    q_si : (M, N) rad/m; wrench : (M, 6) N, N·m
    marker_names : n names, in the order of ``truth.markers``
    sigma_mm : Gaussian noise σ per coordinate, mm (also written in ``sigma``)
    outliers : (row, displacement (3,) mm) pairs; row counts data rows as written, from 0
    approach : (M, N) of ±1, optional: the direction each joint came from, simulated and
        written in the columns ``approach1`` … ``approachN`` times ``written_approach_sign``
        (−1: a file whose approach convention is reversed)

    Returns
    -------
    dict
        ``exact`` (M, n, 3) noise-free positions (m, input order); ``order`` (M,) input index of
        each configuration as written; ``rows`` (R, 2) (configuration, marker) of each row;
        ``outlier_rows`` the rows displaced.
    """
    q = np.atleast_2d(np.asarray(q_si, float))
    wrench = np.atleast_2d(np.asarray(wrench, float))
    exact = marker_positions(chain, truth, q, wrench, approach)
    _, first, pose = np.unique(q, axis=0, return_index=True, return_inverse=True)
    pose_id = np.argsort(np.argsort(first))[pose.ravel()]  # 0-based, by first appearance
    poses = rng.permutation(pose_id.max() + 1) if shuffle else np.arange(pose_id.max() + 1)
    order = np.concatenate([np.flatnonzero(pose_id == p) for p in poses])
    rows = np.array([(c, j) for c in order for j in range(len(marker_names))])
    xyz = exact[rows[:, 0], rows[:, 1]] * 1000.0 + sigma_mm * rng.normal(size=(len(rows), 3))
    for r, d in outliers:
        xyz[r] += d
    qf = q * chain.file_units()
    header = ["pose", *(f"q{k + 1}" for k in range(q.shape[1])), *WRENCH, "marker", "x", "y",
              "z", *(["sigma"] if write_sigma else []),
              *([f"approach{k + 1}" for k in range(q.shape[1])] if approach is not None else [])]
    shown = None if approach is None else \
        (written_approach_sign * np.asarray(approach, float)).astype(int)
    with open(path, "w", newline="", encoding="utf-8") as fh:
        out = csv.writer(fh)
        out.writerow(header)
        for (c, j), p in zip(rows, xyz):
            out.writerow([str(pose_id[c] + 1), *map(repr, qf[c].tolist()),
                          *map(repr, wrench[c].tolist()), marker_names[j], *map(repr, p.tolist()),
                          *([repr(float(sigma_mm))] if write_sigma else []),
                          *(shown[c].tolist() if shown is not None else [])])
    return {"exact": exact, "order": order, "rows": rows,
            "outlier_rows": tuple(int(r) for r, _ in outliers)}


def ball_on_stem_truth(chain, effects=(), seed: int = 31) -> Truth:
    """Issue #31's robot without a tracker: every joint placement off by a rigid transform
    (uniform up to 0.5 mm and 0.05° on each axis), joint offsets up to 0.1°, the tool's ball
    1 mm off its nominal 100 mm on the flange axis, the base at the root; ``effects`` added."""
    rng = np.random.default_rng(seed)
    n = len(chain.joints)
    twists = rng.uniform(-1, 1, (n, 6)) * np.r_[[0.5e-3] * 3, [np.radians(0.05)] * 3]
    offsets = rng.uniform(-1, 1, n) * np.radians(0.1)
    off = rng.normal(size=3)
    ball = np.array([0.0, 0.0, 0.10]) + 1e-3 * off / np.linalg.norm(off)
    return Truth(np.zeros(3), np.zeros(3), ball[None], offsets, twists, tuple(effects))


def ur10_urdf():
    """Path of example-robot-data's ``ur10_robot.urdf``, or None if it is not installed."""
    try:
        files = importlib.metadata.files("example-robot-data") or []
    except importlib.metadata.PackageNotFoundError:
        return None
    found = [f for f in files if str(f).endswith("robots/ur_description/urdf/ur10_robot.urdf")]
    return found[0].locate() if found else None


def probe_poses(chain, truth, q_si, wrench, mount_rotation, mount_position):
    """True pose of a 6-DoF probe on the flange, tracker frame: R (M, 3, 3), t (M, 3) m.

    The probe frame sits at ``mount_position`` (m) turned by ``mount_rotation`` (3, 3) in
    the flange frame; the rest as :func:`marker_positions` (offsets, twists, effects, base).
    """
    q = np.atleast_2d(np.asarray(q_si, float))
    tau, g = joint_torques(chain, q, wrench), gravity_torques(chain, q)
    x = q + truth.offsets
    for e in truth.effects:
        x[:, e.joint] += e.delta(q, tau, g)
    model = truth.robot_model(chain)
    data = model.createData()
    base = pin.SE3(pin.exp3(np.asarray(truth.base_rotvec, float)), truth.base_position)
    mount = pin.SE3(np.asarray(mount_rotation, float), np.asarray(mount_position, float))
    rot, trans = [], []
    for xi in x:
        pin.framesForwardKinematics(model, data, chain.full(xi))
        pose = base * data.oMf[chain.flange] * mount
        rot.append(pose.rotation.copy())
        trans.append(pose.translation.copy())
    return np.array(rot), np.array(trans)


def write_probe_campaign(path, chain, truth, q_si, wrench, mount_rotation, mount_position,
                         sequence: str, sigma_mm: float, angle_sigma_deg: float, rng) -> None:
    """Write a 6-DoF probe file (formats.md §3b): one row per configuration, x, y, z (mm)
    with Gaussian noise σ, angles a, b, c (deg) of scipy's Euler ``sequence`` ("xyz": fixed
    axes = rpy; "XYZ"/"ZYX": intrinsic; "rotvec") of the pose turned by a Gaussian rotation
    vector of σ ``angle_sigma_deg`` per axis (probe frame)."""
    from scipy.spatial.transform import Rotation

    q = np.atleast_2d(np.asarray(q_si, float))
    rot, trans = probe_poses(chain, truth, q, wrench, mount_rotation, mount_position)
    turn = np.radians(angle_sigma_deg) * rng.normal(size=(len(q), 3))
    noisy = Rotation.from_matrix(rot) * Rotation.from_rotvec(turn)
    angles = np.degrees(noisy.as_rotvec() if sequence == "rotvec" else noisy.as_euler(sequence))
    xyz = trans * 1000.0 + sigma_mm * rng.normal(size=trans.shape)
    qf = q * chain.file_units()
    with open(path, "w", newline="", encoding="utf-8") as fh:
        out = csv.writer(fh)
        out.writerow(["pose", *(f"q{k + 1}" for k in range(q.shape[1])), *WRENCH,
                      "x", "y", "z", "a", "b", "c"])
        for i in range(len(q)):
            out.writerow([str(i + 1), *map(repr, qf[i].tolist()),
                          *map(repr, np.atleast_2d(wrench)[i].tolist()),
                          *map(repr, xyz[i].tolist()), *map(repr, angles[i].tolist())])
