"""What every robot program shares: the moves of a design, checked, with load-case words.

A design is turned into an ordered list of :class:`Move` — one per
(pose, load case), in the design's measuring order — with joint values in
controller units (deg; mm for prismatic joints) re-checked against the
robot's joint limits. The format modules only render these moves.
"""
from __future__ import annotations

import re
from dataclasses import dataclass

import numpy as np

from ..errors import DataError

_LIMIT_TOL = 1e-12  # rad or m, as when a design CSV is read
NO_LOAD = "no load"


@dataclass(frozen=True)
class Settings:
    """How the program waits for the measurement at each pose.

    Attributes
    ----------
    name : str
        Program (module) name; a letter then letters, digits or ``_``.
    dwell : float
        Seconds to stand still at each pose before (``handshake``) or while
        (no handshake) the tracker measures.
    handshake : int or None
        None: the program only waits ``dwell`` s at each pose (the tracker
        measures on a timer). An integer n: after the dwell the program sets
        digital output n ("in position"), waits for digital input n
        ("measured") to go high, resets the output and waits for the input to
        drop again. RAPID uses the named signals ``doCalibReady`` and
        ``diCalibDone`` instead of the number.
    """

    name: str = "doe_calib"
    dwell: float = 3.0
    handshake: int | None = None


@dataclass(frozen=True)
class Move:
    """One visit of a pose under one load case.

    Attributes
    ----------
    pose : str
        Pose id of the design.
    index : int
        1-based position of the pose in the design (names its variable).
    q : ndarray, shape (N,)
        Joint values, deg (mm for prismatic joints).
    q_si : ndarray, shape (N,)
        The same in rad (m).
    case, n_cases : int
        1-based load case of this visit and the number of load cases of the pose.
    load : str
        The load to hang, in words ("no load", "250 kg at 0,0,200 mm ...").
    """

    pose: str
    index: int
    q: np.ndarray
    q_si: np.ndarray
    case: int
    n_cases: int
    load: str

    def comment(self) -> str:
        """``pose 3, load case 2 of 2: 250 kg at 0,0,200 mm (flange frame)``."""
        return ascii_text(f"pose {self.pose}, load case {self.case} of {self.n_cases}: "
                          f"{self.load}")

    def instruction(self) -> str:
        """What the operator does before this visit: ``pose 3: hang 250 kg at ...``."""
        todo = "remove the load" if self.load == NO_LOAD else f"hang {self.load}"
        return ascii_text(f"pose {self.pose}: {todo}").replace('"', "'").replace("\\", "/")


def ascii_text(text: str) -> str:
    """``text`` on one line, in printable ASCII (controllers' files are not UTF-8)."""
    text = text.replace("\u00b7", ".").replace("\u00b0", "deg")
    return re.sub(r"[^\x20-\x7e]", "?", " ".join(str(text).split()))


def check_name(name: str, max_length: int) -> str:
    """``name`` if it is a valid program identifier of at most ``max_length`` characters."""
    if not re.fullmatch(r"[A-Za-z][A-Za-z0-9_]*", name) or len(name) > max_length:
        raise DataError(f"program name {name!r}: use a letter followed by letters, digits or '_', "
                        f"at most {max_length} characters")
    return name


def check_limits(design) -> None:
    """Raise :class:`DataError` naming the pose, joint and limit of the first pose outside them."""
    robot, cfg = design.robot, design.configurations
    for pose, q in zip(cfg.pose, cfg.q):
        for joint, v in zip(robot.joints, q):
            if not joint.lower - _LIMIT_TOL <= v <= joint.upper + _LIMIT_TOL:
                k, unit = joint.display_factor, joint.display_unit
                raise DataError(f"pose {pose!r}: joint {joint.name} = {v * k:.6g} {unit} is "
                                f"outside its limits [{joint.lower * k:g}, {joint.upper * k:g}] "
                                f"{unit}")


def _load_words(spec: str) -> str:
    """``250@0,0,200`` → ``250 kg at 0,0,200 mm (flange frame)``."""
    mass, _, com = spec.partition("@")
    return f"{mass} kg at {com or '0,0,0'} mm (flange frame)"


def _wrench_words(wrench) -> str:
    w = np.asarray(wrench, float)
    if not np.any(w):
        return NO_LOAD
    f = ",".join(f"{v:.6g}" for v in w[:3])
    m = ",".join(f"{v:.6g}" for v in w[3:])
    return f"wrench at the flange F = ({f}) N, M = ({m}) N.m (base frame)"


def moves(design) -> list[Move]:
    """Every (pose, load case) of ``design`` in measuring order, limits checked.

    The load of a visit is named from the design's load cases
    (``constraints["loads"]``) when the pose has one unloaded visit followed by
    one per load case; otherwise from its wrench.
    """
    check_limits(design)
    specs = list(design.constraints.get("loads", []))
    factors = design.robot.display_factors
    out = []
    for index, pose in enumerate(design.poses(), start=1):
        wrenches = pose["wrenches"]
        named = len(wrenches) == len(specs) + 1 and not np.any(wrenches[0])
        q = np.asarray(pose["q_deg"], float)
        for case, w in enumerate(wrenches, start=1):
            load = (_load_words(specs[case - 2]) if named and case > 1
                    else _wrench_words(w))
            out.append(Move(str(pose["pose"]), index, q, q / factors, case, len(wrenches), load))
    return out


def load_changes(visits: list[Move]) -> list[bool]:
    """For each move, whether the operator must change the load before it."""
    previous, out = NO_LOAD, []
    for m in visits:
        out.append(m.load != previous)
        previous = m.load
    return out
