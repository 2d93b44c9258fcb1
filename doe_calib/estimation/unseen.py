"""What the readings cannot see, and how far it can move a point they did not measure.

The fit fixes the parameters the readings cannot separate (the result's
fixed list, each with its reason: "not separable from …", "has no effect on
the measured markers …"). Their true values differ from the ones the fit
kept by a deviation δ_d the readings never see: the free parameters took it
up instead, by ``A δ_d`` (``A`` (F, D) from ``B_free A = B_d``, B the
observation matrix of the measured markers). Every measured marker is
predicted as well as before; any other quantity with Jacobian ``J`` moves by::

    G δ_d,   G = J_d − J_free A

which is zero for a measured marker in the tracker frame and not zero for a
TCP never measured, or for the TCP in a robot frame when the readings cannot
split the base pose from the first joint (its rotation about A1 from the A1
offset). With a stated tolerance (prior std) ``s_d`` on each unseen
parameter, that part's covariance is ``G diag(s²) Gᵀ``.

``A`` is the least-squares fit of the free parameters to each unseen one's effect on
the measured markers, at configurations drawn over the joint range the calibration
measured (the result's ``joint_range``; the joint limits when not known), unloaded: the
fit took it up on its readings, there (a joint it held still leaves a dependence that
configurations moving that joint would not have). What they take up is not unseen,
however much or little of it: what they leave is ``G``, and nothing else (no threshold
on the share taken up). A parameter without
effect there — a compliance, unloaded; a marker never read — is not taken up at all
(``A`` is 0) and moves the point by its full effect.

Only the user knows how far an unseen parameter may be from its nominal value. A
tolerance not given is the parameter's typical deviation (1 mm, 1 mrad): the words
(:meth:`UnseenPart.stated`) say so, and ask for the user's.
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from doe_calib.errors import OptionError
from doe_calib.estimation.preparation import not_separable
from doe_calib.io.measurements import Configurations
from doe_calib.model.evaluation import observation_matrix
from doe_calib.model.simulate import random_configurations

#: Configurations over the measured joint range on which the dependence is found (fixed seed).
GENERIC_POSES = 40


def measured_markers(result) -> list[str] | None:
    """The markers a result's readings measured (its residuals per marker); None: not known."""
    return list((result.residuals or {}).get("per_marker", {})) or None


def tolerances(params, names, given: dict | None = None) -> np.ndarray:
    """Stated prior std (SI) of each parameter in ``names``, shape (D,).

    Parameters
    ----------
    params : ParameterSet
    names : sequence of str
    given : dict, optional
        Tolerances (SI) by key, the most specific key winning: a parameter name
        (``dq_a1`` or ``dq_a1:rad``), a block and unit (``geometry:rad``), or a unit
        (``m``, ``rad``).
        A parameter no key names keeps its ``scale``, its typical deviation
        (1 mm for a length, 1 mrad = 0.057° for an angle, 1 µrad/(N·m) for a
        compliance).

    Raises
    ------
    OptionError
        A tolerance that is not a positive finite number.

    Examples
    --------
    >>> from doe_calib import Robot, build_model, examples, Tool
    >>> m = build_model(Robot.from_urdf(examples.ROBOT_URDF), Tool.from_yaml(examples.TOOL_YAML),
    ...                 "joint_offset+geometry")
    >>> tolerances(m.nominal(), ["dq_a1", "g_a1_rz", "g_a1_tz"], {"rad": 1e-3,
    ...            "geometry:rad": 2e-4})
    array([0.001 , 0.0002, 0.001 ])
    """
    given = {} if given is None else dict(given)
    for key, v in given.items():
        if not (np.isfinite(v) and v > 0):
            raise OptionError(f"the tolerance {key!r} of the unseen parameters must be a "
                              f"positive number, not {v}")
    out = []
    for i in params.index(list(names)) if len(names) else []:
        p = params.parameters[i]
        out.append(next((given[k] for k in _keys(p) if k in given), p.scale))
    return np.array(out, float)


def given_tolerances(params, names, given: dict | None = None) -> np.ndarray:
    """Whether a key of ``given`` names each parameter of ``names`` (:func:`tolerances`);
    False: its tolerance is its typical deviation, not the user's. Shape (D,), bool."""
    given = {} if given is None else given
    return np.array([any(k in given for k in _keys(params.parameters[i]))
                     for i in (params.index(list(names)) if len(names) else [])], bool)


def _keys(p) -> tuple:
    """The keys that name parameter ``p`` in a tolerance dict, the most specific first."""
    return p.name, f"{p.name}:{p.unit}", f"{p.block}:{p.unit}", p.unit


@dataclass(frozen=True, eq=False)
class UnseenPart:
    """The parameters the readings cannot see, their stated tolerance and how the fit took them up.

    Attributes
    ----------
    names : tuple of str
        The not-separable parameters (D).
    reasons : tuple of str
        Why each is not separable (the result's words).
    tolerance : ndarray, shape (D,)
        Prior std of each, SI (m, rad, rad/(N·m)): the user's, or its typical deviation.
    absorbed : ndarray, shape (F, D)
        ``A``: the free parameters' change that best reproduces each one's effect on
        the measured markers (least squares; 0 for one without effect on them).
    free : ndarray of bool, shape (P,)
        The parameters that take up (the result's free ones).
    index : ndarray of int, shape (D,)
        Position of each unseen parameter in the parameter vector.
    taken : ndarray of bool, shape (D,)
        Whether it has an effect on the measured markers unloaded (``absorbed`` holds
        how much of it the free parameters take up), or none (a compliance).
    given : ndarray of bool, shape (D,)
        Whether the user gave its tolerance.
    """

    names: tuple
    reasons: tuple
    tolerance: np.ndarray
    absorbed: np.ndarray
    free: np.ndarray
    index: np.ndarray
    taken: np.ndarray
    given: np.ndarray

    def __len__(self) -> int:
        return len(self.names)

    def effect(self, jac, unloaded=None) -> np.ndarray:
        """``G s``: the move of a quantity per unseen parameter at its tolerance, (…, k, D).

        Parameters
        ----------
        jac : ndarray, shape (…, k, P)
            Jacobian of the quantity (a point: k = 3, m) wrt every parameter.
        unloaded : ndarray, shape (…, k, P), optional
            The same without the wrench, for the columns taken up: ``A`` holds
            their dependence unloaded, and a load adds only the change of its
            deflection with the geometry (second order: compliance × deviation,
            µm), which the readings of a loaded campaign do not split either.
        """
        jac = np.asarray(jac, float)
        base = jac if unloaded is None else np.asarray(unloaded, float)
        g = base[..., self.index] - base[..., self.free] @ self.absorbed
        g[..., ~self.taken] = jac[..., self.index[~self.taken]]
        return g * self.tolerance

    def std_3d(self, jac, unloaded=None) -> np.ndarray:
        """3-D std of a point's unseen part, ``√tr(G diag(s²) Gᵀ)``, shape (…,), m."""
        return np.sqrt(np.sum(self.effect(jac, unloaded) ** 2, axis=(-2, -1)))

    def largest(self, jac, unloaded=None, count: int = 3) -> list[str]:
        """The ``count`` unseen parameters moving the quantity most (summed over its rows)."""
        size = np.sqrt(np.sum(self.effect(jac, unloaded) ** 2,
                              axis=tuple(range(np.ndim(jac) - 1))))
        order = np.argsort(-size, kind="stable")[:count]
        return [self.names[i] for i in order if size[i] > 0]

    def stated(self, params) -> str:
        """The tolerances in words, display units: ``1 mm (7 parameters), 0.0573 deg (9 …)``,
        those not given by the user said to be each parameter's typical deviation."""
        by = {}
        for name, s, given in zip(self.names, self.tolerance, self.given):
            p = params.parameters[params.position(name)]
            key = (f"{s * p.display_factor:.3g} {p.display_unit}", bool(given))
            by[key] = by.get(key, 0) + 1
        return ", ".join(f"{k} ({n} parameter{'s' if n > 1 else ''}"
                         f"{'' if given else ', not given: the typical deviation'})"
                         for (k, given), n in by.items())

    @property
    def defaulted(self) -> bool:
        """Whether some tolerance is not the user's (the words then ask for it)."""
        return not bool(np.all(self.given))


#: What the words say when some tolerance is not the user's.
ASK = ("state how far they may be from the nominal (tolerance= of predict and compensate; "
       "doe-calib compensate --unseen-tolerance, e.g. 0.2mm geometry:0.01deg)")


def unseen_part(model, params, markers=None, tolerance: dict | None = None,
                taking=None, within=None) -> UnseenPart:
    """The unseen part of a result: its not-separable parameters and how the fit took them up.

    Parameters
    ----------
    model : Model
        The model the result was identified with.
    params : ParameterSet
        The result's parameters; the unseen ones are those the rank analysis fixed
        (:func:`~doe_calib.estimation.preparation.not_separable`).
    markers : sequence of str, optional
        The markers the readings measured (default all of the tool's).
    tolerance : dict, optional
        Stated prior std of the unseen parameters (SI) by name, ``block:unit`` or unit
        (:func:`tolerances`); default each parameter's scale, said in words.
    taking : ndarray of bool, shape (P,), optional
        Held parameters that take up too (besides the free ones): a motion the
        readings cannot see and the caller states in words
        (:func:`~doe_calib.estimation.sockets.frame_unseen_part`).
    within : ndarray, shape (N, 2), optional
        The joint range the readings covered, rad (m): the result's ``joint_range``.
        Default the joint limits.

    Returns
    -------
    UnseenPart

    Examples
    --------
    >>> from doe_calib import Robot, Tool, build_model, examples
    >>> m = build_model(Robot.from_urdf(examples.ROBOT_URDF), Tool.from_yaml(examples.TOOL_YAML),
    ...                 "joint_offset")
    >>> from doe_calib.estimation.preparation import NOT_SEPARABLE
    >>> p = m.nominal().fixed(["dq_a1"], "offset of joint a1 (dq_a1) is not separable from "
    ...                       "base rotation vector z (base_rz)" + NOT_SEPARABLE)
    >>> part = unseen_part(m, p)
    >>> part.names, part.tolerance, part.given
    (('dq_a1',), array([0.001]), array([False]))
    >>> bool(abs(part.absorbed).max() > 0.5)  # the base's turn takes it up
    True
    """
    names = not_separable(params)
    index = np.array(params.index(names), int) if names else np.zeros(0, int)
    free = np.asarray(params.free, bool).copy()
    free[index] = False
    if taking is not None:
        free |= np.asarray(taking, bool)
    absorbed = np.zeros((int(free.sum()), len(names)))
    taken = np.ones(len(names), bool)
    if names:
        rng = np.random.default_rng(0)
        q = random_configurations(model.robot, GENERIC_POSES, rng) if within is None else \
            rng.uniform(*np.asarray(within, float).T, (GENERIC_POSES, len(within)))
        cfg = Configurations.from_arrays(q)
        _, b = observation_matrix(model, params.values, cfg)
        if markers is not None:
            b = b[:, [model.tool.index(n) for n in markers]]
        b = b.reshape(-1, b.shape[-1]) * params.scales   # columns at their typical size
        b_free, b_dep = b[:, free], b[:, index]
        # least squares: a column without effect (a compliance, unloaded; an unmeasured
        # marker) gets A = 0, and its full effect under the row's load counts
        absorbed = np.linalg.lstsq(b_free, b_dep, rcond=None)[0]
        absorbed *= params.scales[free][:, None] / params.scales[index]
        taken = np.linalg.norm(b_dep, axis=0) > 0
    reasons = tuple(params.fixed_reason[i] for i in index)
    return UnseenPart(tuple(names), reasons, tolerances(params, names, tolerance),
                      absorbed, free, index, taken,
                      given_tolerances(params, names, tolerance))


def unseen_notes(effect, seen, marker, names, part: UnseenPart, params) -> tuple:
    """Words for the readings whose unseen part exceeds the fit's own std; () when none does.

    Parameters
    ----------
    effect : ndarray, shape (K, 3, D)
        :meth:`UnseenPart.effect` of each reading, m.
    seen : ndarray, shape (K,)
        3-D std from the fit's covariance, m.
    marker : ndarray of int, shape (K,)
        Index of each reading's marker in ``names``.
    """
    unseen = np.sqrt(np.sum(effect ** 2, axis=(1, 2)))
    over = unseen > np.asarray(seen)
    if not over.any():
        return ()
    which = sorted({names[k] for k in np.asarray(marker)[over]})
    size = np.sqrt(np.sum(effect[over] ** 2, axis=(0, 1)))
    top = [part.names[i] for i in np.argsort(-size, kind="stable")[:3] if size[i] > 0]
    return (f"{int(over.sum())} predicted reading(s) of marker(s) {', '.join(which)} rest on "
            f"what the calibration's readings could not see ({', '.join(top)}): at the "
            f"tolerances ({part.stated(params)}) up to {np.max(unseen) * 1000:.3g} mm (1σ, "
            f"3-D), included in the std; measure those markers in the calibration to remove "
            f"it{'; ' + ASK if part.defaulted else ''}",)
