"""The protocol every physical effect implements.

An effect contributes named parameters and one or more symbolic corrections
to the kinematic chain (see :mod:`doe_calib.model.kinematics`):

* ``joint_correction``: an additive correction of each joint coordinate
  before any load is applied (offsets, encoder scale, cyclic errors);
* ``placement``: a rigid correction applied right after the nominal
  placement of joint ``k`` (``k = N`` is the flange);
* ``deflection``: an additive joint deflection caused by the joint torques
  ``tau`` of the applied wrench (compliance, backlash).

Each returns ``None`` when the effect has nothing to say there. Adding an
effect is a new module with a subclass of :class:`Effect` and one line in
:mod:`doe_calib.model.effects` (the default registry).

An effect also owns what is known about it: the words a diagnosis verdict
uses when it finds the effect missing (:attr:`Effect.phrase`, :meth:`Effect.describe`),
and, on each of its parameters (:class:`~doe_calib.model.parameters.Parameter`),
the unit, the physical ``bounds`` (a compliance is ≥ 0), the ``plausible``
range (a cyclic error within ±2°) and what the ``sign`` means. Diagnosis,
plausibility checks, identifiability and simulated truths read them there.

An effect may take arguments, written in the model string as
``name(arg, key=value)``, e.g. ``cyclic(j3, harmonics=2)``: they are the
subclass's constructor arguments. A joint is named ``jK`` (K = 1 … N along
the chain) or by its URDF name; :func:`joint_index` resolves it.
"""
from __future__ import annotations

from dataclasses import dataclass

import casadi as ca

from doe_calib.errors import ModelError


@dataclass(frozen=True)
class ChainSymbols:
    """The symbols an effect may use.

    Attributes
    ----------
    robot : Robot
    q : casadi.SX, shape (N, 1)
        Joint positions as commanded, rad or m.
    env : casadi.SX, shape (1 + N, 1)
        Environment variables (:func:`doe_calib.io.measurements.env_fields`): ``env[0]``
        the temperature (°C, NaN when not measured), ``env[1 + k]`` the
        direction from which joint k reached the configuration (+1, −1, 0).
    p : dict of str to casadi.SX
        Every model parameter by name (SI).
    wrench : casadi.SX, shape (6, 1), or None
        The applied wrench (N, N·m) at the flange origin, base frame; set by
        :func:`~doe_calib.model.kinematics.flange_pose`.
    gravity : casadi.SX, shape (N, 1), or None
        Joint torques (N·m, N for a prismatic joint) that the robot's own
        weight exerts at the commanded q (:func:`~doe_calib.model.kinematics.gravity_torques`);
        set by :func:`~doe_calib.model.kinematics.flange_pose` when an effect
        ``uses_gravity``.
    """

    robot: object
    q: ca.SX
    env: ca.SX
    p: dict
    wrench: ca.SX | None = None
    gravity: ca.SX | None = None


def joint_index(robot, joint) -> int:
    """Index (0-based, along the chain) of a joint given as ``jK`` (1-based), K, or its name."""
    names = [j.name for j in robot.joints]
    text = str(joint)
    if text in names:
        return names.index(text)
    digits = text[1:] if text[:1] in "jJ" else text
    if digits.isdigit() and 1 <= int(digits) <= len(names):
        return int(digits) - 1
    raise ModelError(f"no joint {text!r} in robot {robot.name!r}: use j1 … j{len(names)} "
                     f"or one of {', '.join(names)}")


def at_joint(s: ChainSymbols, k: int, value) -> ca.SX:
    """A correction of one joint: SX (N, 1), ``value`` at joint ``k`` (0-based), 0 elsewhere."""
    out = ca.SX.zeros(s.robot.n_joints, 1)
    out[k] = value
    return out


class Effect:
    """Base class: no parameters and no correction. Subclasses override.

    A subclass with arguments passes them on, ``super().__init__(joint, harmonics=h)``,
    so that :meth:`spec` writes them back into the model string.
    """

    #: Name used in ``--model`` strings, e.g. ``joint_offset``.
    name = ""
    #: Whether the effect sits on one joint, given as its first argument (``cyclic(j3)``).
    per_joint = False
    #: Whether the effect reads ``ChainSymbols.gravity`` (the robot's own weight).
    uses_gravity = False
    #: Whether every rotation its ``placement`` returns is an exact rotation at any parameter
    #: value (the observation matrix is then formed from the flange's twist,
    #: :mod:`doe_calib.model.twist_jacobian`).
    exact_rotations = True
    #: What a verdict calls the effect when it is missing, e.g. "backlash of joint {joint}";
    #: ``{joint}`` becomes "3 (a3)". Empty: "effect <spec>".
    phrase = ""
    #: Why a fitted value outside its parameter's ``plausible`` range is implausible.
    implausible_words = "beyond the range plausible for it"

    def __init__(self, *args, **options):
        self._args = tuple(str(a) for a in args)
        self._options = {k: v for k, v in options.items()}

    def parameters(self, robot) -> list:
        """The effect's parameters (list of :class:`~doe_calib.model.parameters.Parameter`)."""
        return []

    def joint_correction(self, s: ChainSymbols):
        """Additive joint-coordinate correction, SX (N, 1), or None."""
        return None

    def placement(self, s: ChainSymbols, k: int):
        """Rigid correction ``(R, t)`` after the nominal placement of joint k, or None."""
        return None

    def deflection(self, s: ChainSymbols, tau: ca.SX):
        """Additive joint deflection (N, 1) from joint torques ``tau`` (N·m or N), or None."""
        return None

    @classmethod
    def candidates(cls, robot, configurations=None) -> list:
        """The instances model diagnosis tries when this effect is missing.

        One instance for a whole-robot effect; a per-joint effect (``per_joint``)
        one per joint, e.g. ``[GearRatio("j1"), …]``, with default options.
        An effect with several shapes offers each as a separate candidate
        (variants compete by cross-validation); ``configurations``, the
        measured ones, lets a shape adapt to the range the data cover.
        """
        if cls.uses_gravity and not robot.has_inertials:
            return []
        if cls.per_joint:
            return [cls(f"j{k + 1}") for k in range(robot.n_joints)]
        return [cls()]

    def describe(self, robot) -> str:
        """The effect in a verdict's words, e.g. "a cyclic (transmission) error of joint 3 (a3)"."""
        if not self.phrase:
            return f"effect {self.spec()}"
        joint = ""
        if self.joint is not None:
            k = joint_index(robot, self.joint)
            joint = f"{k + 1} ({robot.joints[k].name})"
        return self.phrase.format(joint=joint)

    @property
    def joint(self):
        """The joint selector the effect sits on (e.g. ``"j3"``), or None for a whole-robot one.

        A per-joint effect takes its joint as its first argument.
        """
        return self._args[0] if self.per_joint and self._args else None

    @property
    def uses_torque(self) -> bool:
        """Whether :meth:`deflection` is implemented (the chain then computes torques)."""
        return type(self).deflection is not Effect.deflection

    def spec(self) -> str:
        """The effect as written in a ``--model`` string, e.g. ``cyclic(j3,harmonics=2)``."""
        words = list(getattr(self, "_args", ())) + \
            [f"{k}={v}" for k, v in getattr(self, "_options", {}).items()]
        return f"{self.name}({','.join(words)})" if words else self.name
