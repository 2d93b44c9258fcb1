"""A user-defined effect for doe-calib: progressive (non-linear) joint stiffness.

Use it with ``--effect-file``::

    doe-calib identify --effect-file example_effect.py \\
        --model joint_offset+joint_compliance+progressive_stiffness(j2) ...

A gearbox does not deflect in proportion to its torque: the stiffness of
strain-wave and cycloidal drives changes with the load. On top of the
linear compliance (``joint_compliance``, deflection ``c τ``) this effect adds
the first non-linear term, odd in the torque so that the deflection still
reverses with it::

    Δq_k = a · (τ_k / τ_ref) · |τ_k / τ_ref|

``a`` (rad) is the extra deflection of joint k at the reference torque
``τ_ref`` = 1000 N·m; it is negative for a drive that stiffens under load.
Identifying it needs load cases with large and varied joint torques (a
heavy mass at several poses). Revolute joints: for a prismatic joint ``τ_k``
is a force, N, and ``τ_ref`` 1000 N.

See :mod:`doe_calib.model.effects.user` for the file protocol.
"""
import casadi as ca

NAME = "progressive_stiffness"
PER_JOINT = True        # written progressive_stiffness(j2); diagnosis tries every joint

#: Reference torque, N·m: ``a`` is the quadratic deflection there.
TAU_REF = 1000.0

PARAMETERS = [
    ("a", "rad", 1e-4, f"quadratic deflection at {TAU_REF:g} N·m (τ|τ| term)"),
]


def deflection(q, env, p, tau, joint=None):
    """Additive joint deflection, N values (rad), from the joint torques ``tau`` (N·m)."""
    x = tau[joint] / TAU_REF
    out = ca.SX.zeros(q.numel(), 1)
    out[joint] = p["a"] * x * ca.fabs(x)
    return out
