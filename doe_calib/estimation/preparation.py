"""What every estimator does first: start values, base registration, the rank analysis.

The base pose starts from a point-set registration of the tracker's readings;
the parameters the data cannot separate are fixed (at their current values) with
the reason in words. Readings that are all socket contacts cannot see the base
pose, a rigid motion of the whole arm or its scale: those are fixed first, said
in words of their own (:func:`fix_unseen_by_contacts`). Plane touches cannot see them
either; ballbar readings see the scale (their lengths are known), not the rest. Sockets
of given position see what points read do: at least three not on one line, everything;
at one point or on one line, not the base's turn about it (:func:`fix_base_turn`). Planes
of given position see the base along their normals (:func:`fix_unseen_by_given_planes`).
"""
from __future__ import annotations

import warnings

import numpy as np

from doe_calib.errors import ConditioningWarning, DataError, IdentifiabilityWarning
from doe_calib.estimation.identifiability import analyse, blind_motion_words
from doe_calib.estimation.observation_count import check_count
from doe_calib.estimation.planes import check_planes
from doe_calib.estimation.registration import register
from doe_calib.estimation.weighted_residuals import (
    eliminated_rows,
    marker_points,
    reduce_jacobian,
)
from doe_calib.model.evaluation import observation_matrix
from doe_calib.model.rotations import matrix_to_rotation_vector, rotation_vector_to_matrix

#: Condition number of the observation matrix above which the fit warns.
COND_WARN = 1e6
#: How the reason of every parameter the rank analysis fixed ends.
NOT_SEPARABLE = "; fixed at its current value"
#: Why the base pose is fixed when every reading is a socket contact.
BASE_UNSEEN = "socket contacts cannot see the robot's base pose: fixed at the URDF's root"
#: Why the first joint's placement and offset are then fixed too.
ARM_UNSEEN = ("socket contacts cannot see a rigid motion of the whole arm (the first joint's "
              "placement, and its offset, turn and shift every contact and socket alike): "
              "fixed at its current value with the base pose")
#: Why one link length is then held: the words end with the length.
SCALE_UNSEEN = ("socket contacts cannot see the robot's scale without a known length (the "
                "whole arm and the sockets grown alike fit the same): held at its current value "
                "to fix the scale, the link length it sets")
#: Why the base rotation is fixed when one socket's position is given: a turn about it.
POINT_UNSEEN = ("socket contacts with one socket of given position cannot see the base's turn "
                "about that point: the base rotation held at the URDF's root axes")
#: Why a base rotation is fixed when the given sockets lie on one line (their ids follow).
LINE_UNSEEN = ("socket contacts whose given positions lie on one line cannot see the base's "
               "turn about that line: the base rotation's component about it held at the "
               "turn least from the URDF's root axes (sockets {})")
#: How the reasons of :func:`fix_base_turn` begin.
_TURN_REASONS = (POINT_UNSEEN, LINE_UNSEEN.split("{")[0])
#: Given socket positions closer than this (m) are one point; off a line by less: on it.
APART = 1e-3


#: What each instrument without coordinates reads, and what it reads against.
_INSTRUMENTS = {"socket": ("socket contacts", "contact and socket", "sockets"),
                "plane": ("plane touches", "touch and plane", "planes"),
                "ballbar": ("ballbar readings", "ballbar reading and pivot", "pivots")}


def unseen_words(instruments) -> tuple:
    """``(base, arm, scale)`` reasons, in words, for readings of ``instruments`` (some of
    "socket", "plane", "ballbar"): those of sockets alone are :data:`BASE_UNSEEN`,
    :data:`ARM_UNSEEN` and :data:`SCALE_UNSEEN`.

    Examples
    --------
    >>> unseen_words(["plane"])[0]
    "plane touches cannot see the robot's base pose: fixed at the URDF's root"
    """
    said = [_INSTRUMENTS[k] for k in _INSTRUMENTS if k in instruments]
    read, fixed = (" and ".join(w[i] for w in said) for i in (0, 2))
    alike = ", ".join(w[1] for w in said)
    return (BASE_UNSEEN.replace("socket contacts", read, 1),
            ARM_UNSEEN.replace("socket contacts", read, 1).replace("contact and socket", alike),
            SCALE_UNSEEN.replace("socket contacts", read, 1).replace("the sockets", f"the {fixed}"))


def instruments(measurements) -> list:
    """The instruments without coordinates among ``measurements``: "socket" (seated
    contacts), "plane", "ballbar"."""
    seated = measurements.contact & ~measurements.touch & ~measurements.ballbar
    return [k for k, used in (("socket", seated), ("plane", measurements.touch),
                              ("ballbar", measurements.ballbar)) if used.any()]


def not_separable(params) -> list[str]:
    """Names of the parameters the rank analysis fixed (their reason ends in
    :data:`NOT_SEPARABLE`), whatever values they hold."""
    return [p.name for p, free, why in zip(params.parameters, params.free, params.fixed_reason)
            if not free and why.endswith(NOT_SEPARABLE)]


def register_base(model, measurements, params):
    """Start values of the base pose from a point-set registration of all readings.

    The markers are placed with the current robot parameters (base at the
    identity), then rotated and shifted onto the readings: any tracker
    placement and any angle is found, no small-angle assumption.
    """
    base = params.index("base")
    v = params.values.copy()
    v[base] = 0.0
    robot_pts = marker_points(model, measurements, v)
    rot, t = register(robot_pts, measurements.xyz, 1.0 / measurements.sigma ** 2)
    v[base[:3]] = t
    v[base[3:]] = matrix_to_rotation_vector(rot)
    return params.with_values(v)


def fix_unseen_by_contacts(robot, params, read=("socket",)):
    """What readings that are all socket contacts cannot see, fixed and said in words.

    Contacts compare the marker to points of unknown position: a rigid motion or a
    growth of the whole arm moves the sockets with it, and fits the same. Fixed are the
    base pose, at the identity (the URDF's root frame, :data:`BASE_UNSEEN`); the first
    joint's placement and offset, at their values (:data:`ARM_UNSEEN`); and, when the
    model has placement translations, the one along the longest nominal link, at its
    value (:data:`SCALE_UNSEEN`): the scale. Exact null directions of these readings'
    Jacobian only where every socket's contacts meet, so the rank analysis at the
    nominal model does not find them; left free, a fit can shrink the arm.

    ``read``: the instruments of the readings (:func:`instruments`), whose words
    (:func:`unseen_words`) are said. Plane touches are as blind as contacts (a plane moves
    and grows with the arm; what else they miss, a plane's own shift along its normal and
    its tilt, is eliminated, and the rank analysis finds any more). A ballbar's known
    length sees the scale: with one, no length is held.
    """
    base_words, arm_words, scale_words = unseen_words(read)
    base = params.index("base")
    v = params.values.copy()
    v[base] = 0.0
    params = params.with_values(v).fixed([params.names[i] for i in base], base_words)
    first = robot.joints[0].name
    arm = [n for n in (f"dq_{first}", *(f"g_{first}_{r}{a}" for r in "tr" for a in "xyz"))
           if n in params.names]
    params = params.fixed(arm, arm_words) if arm else params
    if "ballbar" in read or any(why.startswith(scale_words) for why in params.fixed_reason):
        return params  # the scale is seen, or (a refit of the kept parameters) already held
    name, length = _longest_link(robot, params)
    return params.fixed([name], f"{scale_words} ({length * 1000.0:.1f} mm)") if name \
        else params


def fix_unseen_by_given(model, measurements, params, start: bool = True):
    """Start values of the base, and the scale held, when the only readings with coordinates
    are contacts in sockets of given position at one point or on one line (formats.md §3;
    the base's turn they cannot see: :func:`fix_base_turn`, after the rank analysis).

    The base starts at the least turn from the URDF's root that puts their contacts on
    them (``start``; not on a refit, whose base is the fit's). At one point, without a
    ballbar's known length, the placement translation along the longest nominal link is
    held at its value (:data:`SCALE_UNSEEN`): the scale.
    """
    spread = _spread(given_sockets(measurements))
    params = _start_base(model, measurements, params, spread) if start else params
    if spread == 1 or measurements.ballbar.any() or \
            any(why.startswith(SCALE_UNSEEN) for why in params.fixed_reason):
        return params
    name, length = _longest_link(model.robot, params)
    return params.fixed([name], f"{SCALE_UNSEEN} ({length * 1000.0:.1f} mm)") if name \
        else params


#: Why a base translation is held when planes of given position leave a shift unseen.
PLANES_SHIFT = ("plane touches on planes of given position cannot see the base's shift "
                "parallel to every one of them: the base translation's component along it held "
                "at its current value (planes {})")
#: Why a base rotation is held when the planes of given position are all parallel.
PLANES_TURN = ("plane touches on parallel planes of given position cannot see the base's turn "
               "about their normal: the base rotation's component about it held at its current "
               "value (planes {})")
#: Why a link length is held when the planes of given position share a point.
PLANES_SCALE = ("plane touches on planes of given position that share a point cannot see the "
                "robot's scale about that point (the arm grown about it moves every touch "
                "within its plane): held at its current value to fix the scale, the link "
                "length it sets")


def given_planes(measurements) -> dict:
    """Plane id → (a point of it (3,), m; its unit normal (3,)) for each plane whose touches
    give its position (formats.md §3); empty without."""
    out = {}
    for i in np.flatnonzero(measurements.given_plane).tolist():
        out.setdefault(measurements.plane_names[measurements.plane[i]],
                       (measurements.xyz[i], measurements.plane_normal[i]))
    return out  # a plane's rows agree (the reader's check)


def fix_unseen_by_given_planes(model, measurements, params) -> tuple:
    """What readings without coordinates, some of them touches of planes of given position,
    cannot see of the base and the scale, held and said in words; ``(params, reasons)``.

    A rigid motion keeps a plane in place only if it shifts along the plane and turns about
    its normal: the base's shift parallel to every given plane is not seen (none with three
    independent normals; :data:`PLANES_SHIFT`), nor its turn about their normal when all are
    parallel (:data:`PLANES_TURN`; two or more non-parallel planes see the tilt and turn).
    The arm grown about a point on every given plane moves each touch within its plane: when
    the planes share a point (any one or two; three with independent normals meet at one)
    and no ballbar gives a length, the placement translation along the longest nominal link
    is held (:data:`PLANES_SCALE`). The base starts where the model has it (the URDF's root
    for a nominal model): give the planes in a frame near it. The rest (the first joint's
    placement against the base's) the rank analysis finds, as for tracker readings.
    """
    planes = given_planes(measurements)
    names = ", ".join(planes)
    point = np.array([p for p, _ in planes.values()])
    normal = np.array([n for _, n in planes.values()])
    _, sv, vt = np.linalg.svd(normal)
    rank = int(np.sum(sv > APART))
    base, reasons = params.index("base"), []
    for u in vt[rank:]:
        free = [i for i in base[:3].tolist() if params.free[i]]
        if free:
            pick = max(free, key=lambda i: abs(u[i - base[0]]))
            params = params.fixed([params.names[pick]], PLANES_SHIFT.format(names))
            reasons.append(PLANES_SHIFT.format(names))
    if rank == 1:
        turn = _base_turn_about(params, {"0": np.zeros(3), "1": normal[0]})
        if params.free[turn]:
            params = params.fixed([params.names[turn]], PLANES_TURN.format(names))
            reasons.append(PLANES_TURN.format(names))
    d = np.sum(point * normal, axis=1)
    shared = np.linalg.lstsq(normal, d, rcond=None)[0]
    if measurements.ballbar.any() or np.max(np.abs(normal @ shared - d)) > APART or \
            any(why.startswith(PLANES_SCALE) for why in params.fixed_reason):
        return params, reasons
    name, length = _longest_link(model.robot, params)
    if name:
        params = params.fixed([name], f"{PLANES_SCALE} ({length * 1000.0:.1f} mm)")
        reasons.append(PLANES_SCALE)
    return params, reasons


def _only_given(measurements) -> bool:
    """Whether every reading with coordinates is a contact in a socket of given position
    (no tracker reading), and some is."""
    read = ~measurements.contact
    return measurements.socket is not None and read.any() and \
        bool(np.all(measurements.socket[read] >= 0))


def fix_base_turn(measurements, params):
    """The base's turn that given socket positions at one point, or on one line, cannot
    see, fixed and said in words; ``params`` unchanged for other readings.

    After the rank analysis, which fixed what moves the whole arm as the base does: the
    base rotation (:data:`POINT_UNSEEN`), or its component a turn about the line changes
    most (:data:`LINE_UNSEEN`), is then the only way left to turn the arm so.
    """
    points = given_sockets(measurements)
    if not points or not _only_given(measurements) or _spread(points) >= 2:
        return params
    rotation = params.index("base")[3:]
    if _spread(points) == 0:
        return params.fixed([params.names[i] for i in rotation], POINT_UNSEEN)
    return params.fixed([params.names[_base_turn_about(params, points)]],
                        LINE_UNSEEN.format(", ".join(points)))


def given_sockets(measurements) -> dict:
    """Socket id → its given position (3,), m, for each socket whose contacts give it
    (formats.md §3); empty without."""
    if measurements.socket is None:
        return {}
    out = {}
    for i in np.flatnonzero((measurements.socket >= 0) & ~measurements.contact).tolist():
        out.setdefault(measurements.socket_names[measurements.socket[i]], measurements.xyz[i])
    return out  # a socket's rows agree (the reader's check)


def _spread(points: dict) -> int:
    """0 for no point or one, 1 for points on one line, 2 for points spanning a plane
    (apart by more than :data:`APART`, m)."""
    if len(points) < 2:
        return 0
    p = np.array(list(points.values()))
    return int(np.sum(np.linalg.svd(p - p.mean(0), compute_uv=False) > APART))


def _start_base(model, measurements, params, spread: int):
    """Start values of the base pose from given sockets on a line (``spread`` 1) or at one
    point (0): the turn least from the URDF's root that puts the model's contacts on them."""
    seen = measurements.subset(~measurements.contact)
    base = params.index("base")
    v = params.values.copy()
    v[base] = 0.0
    robot_pts, w = marker_points(model, seen, v), seen.sigma ** -2.0
    rot = np.eye(3)
    if spread == 1:
        a, b = (_axis(x, w) for x in (robot_pts, seen.xyz))
        b = b * np.sign(np.sum(w * ((robot_pts - robot_pts.mean(0)) @ a) *
                               ((seen.xyz - seen.xyz.mean(0)) @ b)) or 1.0)
        turn = np.cross(a, b)
        rot = rotation_vector_to_matrix(turn / max(np.linalg.norm(turn), 1e-300) *
                                        np.arctan2(np.linalg.norm(turn), a @ b))
    v[base[:3]] = np.average(seen.xyz, 0, w) - rot @ np.average(robot_pts, 0, w)
    v[base[3:]] = matrix_to_rotation_vector(rot)
    return params.with_values(v)


def _axis(points, w) -> np.ndarray:
    """The weighted points' principal direction (3,), unit."""
    c = points - np.average(points, 0, w)
    return np.linalg.svd(c * np.sqrt(w)[:, None], full_matrices=False)[2][0]


def _base_turn_about(params, points: dict) -> int:
    """Index of the base's rotation parameter that a turn about the line through
    ``points`` changes most (fixing it removes that turn)."""
    p = np.array(list(points.values()))
    u = np.linalg.svd(p - p.mean(0))[2][0]
    rot = params.index("base")[3:]
    r0 = params.values[rot]
    moved = matrix_to_rotation_vector(rotation_vector_to_matrix(1e-6 * u) @
                                      rotation_vector_to_matrix(r0))
    return int(rot[np.argmax(np.abs(moved - r0))])


#: Fraction of a parameter's effect on the touched markers below which plane touches do not
#: see it (:func:`fix_unseen_by_touches`); below the second, the rank analysis finds it.
MIN_SEEN_BY_TOUCHES, EXACTLY_UNSEEN = 0.01, 1e-6
#: Why a parameter is fixed by :func:`fix_unseen_by_touches`.
WITHIN_PLANES = ("plane touches cannot see it: it moves every touch within its plane, or the "
                 "plane with it (the data keep less than 1 % of its effect): fixed at its "
                 "current value")


def fix_unseen_by_touches(model, measurements, params):
    """Fix, said in words, the free parameters whose effect on the markers of readings that
    are all contacts, some of them plane touches, the eliminated residuals keep less than
    :data:`MIN_SEEN_BY_TOUCHES` of (and more than :data:`EXACTLY_UNSEEN`: the rank
    analysis says why those are not seen): a touch sees an error only along its plane's
    normal, and less what moves the whole plane.

    These are near, not exact, null directions: the planes' normals are seen only as well
    as the start values place the touches (with a table top alone, under an arm standing
    on it, the shoulder's offset from the first joint's axis moves every touch parallel to
    the table: left free, a fit gives it a std of millimetres).
    """
    x, b = observation_matrix(model, params.values, measurements.configurations)
    c, j, every = measurements.config, measurements.marker, np.arange(len(measurements))
    free = np.flatnonzero(params.free)
    whole = b[c, j][:, :, free]
    seen = eliminated_rows(measurements, every, x[c, j], whole)
    weight = measurements.sigma[:, None, None] ** -2.0
    effect = np.sqrt(np.sum(whole ** 2 * weight, axis=(0, 1)))
    kept = np.sqrt(np.sum(seen ** 2 * weight, axis=(0, 1)))
    blind = (kept < MIN_SEEN_BY_TOUCHES * effect) & (kept > EXACTLY_UNSEEN * effect)
    return params.fixed([params.names[i] for i in free[blind]], WITHIN_PLANES) \
        if blind.any() else params


def _longest_link(robot, params) -> tuple:
    """The placement translation (name) along the longest nominal link after the first
    joint, and that length (m); (None, 0) when the model has none free."""
    frames = [(j.name, j.placement_matrix) for j in robot.joints[1:]] + \
        [("flange", np.array(robot.flange_placement, float).reshape(4, 4))]
    best = (None, 0.0)
    for frame, m in frames:
        local = m[:3, :3].T @ m[:3, 3]  # the link in the frame the error is expressed in
        for a, x in zip("xyz", local):
            name = f"g_{frame}_t{a}"
            if abs(x) > abs(best[1]) and name in params.names and \
                    params.free[params.names.index(name)]:
                best = (name, float(abs(x)))
    return best


def _fixed_sentence(params, names) -> str:
    """One sentence: how many parameters were fixed as not separable, counted by block."""
    blocks = [params.parameters[i].block for i in params.index(names)]
    by_block = ", ".join(f"{blocks.count(b)} {b}" for b in dict.fromkeys(blocks))
    return (f"{len(names)} parameters fixed as not separable by these data ({by_block}); "
            f"the reason for each is in the result (the result JSON's \"fixed\" list; "
            f"doe-calib identify --verbose prints them)")


def fix_unidentifiable(model, measurements, params, tol: float = 1e-7, reduction=None):
    """Fix (at their current values) the free parameters the data cannot separate.

    ``reduction``: of ``[J | r]`` for all parameters at ``params.values``, when at hand.
    Returns the new parameter set, the warnings issued, in words, and what each kept
    parameter absorbs of the fixed ones (:attr:`Identifiability.absorbed`).

    Raises
    ------
    DataError
        Readings all without coordinates that separate as many parameters as they have
        coordinates, and not all of them
        (:func:`~doe_calib.estimation.observation_count.check_count`).
    """
    red = reduce_jacobian(model, measurements, params.values) if reduction is None \
        else reduction
    ident = analyse(red.r_factor, params, tol=tol)  # RᵀR = JᵀJ: same columns' geometry
    check_count(measurements, params, ident)
    notes = []
    blind, unseen = blind_motion_words(model.tool), False
    if ident.dependent:
        names = [n for n, _ in ident.dependent]
        marker_names = [params.names[i] for i in params.index("markers")]
        for name, why in ident.dependent:
            if blind and any(f"({m})" in why for m in marker_names):
                why += f" ({blind.split(':')[0]})"
                unseen = True
            params = params.fixed([name], why + NOT_SEPARABLE)
        warnings.warn(_fixed_sentence(params, names), IdentifiabilityWarning, stacklevel=3)
        notes.append(f"{len(names)} parameters fixed as not identifiable (see the fixed list)")
    if unseen:
        notes.append(blind)
    if ident.condition_number > COND_WARN:
        msg = (f"the observation matrix is poorly conditioned (condition number "
               f"{ident.condition_number:.2g}); the weakest combination involves "
               f"{', '.join(ident.weakest)}: these will have large standard deviations")
        warnings.warn(msg, ConditioningWarning, stacklevel=3)
        notes.append(msg)
    return params, notes, ident.absorbed


def prepare(model, measurements, params=None, register: bool = True) -> tuple:
    """Common start of every estimator: start values, base registration, rank analysis.

    Returns
    -------
    params : ParameterSet
        Start values, with the parameters the data cannot separate fixed.
    notes : list of str
        The warnings issued, in words.
    reduction : Reduction
        Of ``[J | r]`` for all parameters at the start values (the rank analysis' own;
        the point estimator's first Jacobian pass).
    absorbed : dict
        Kept parameter → the fixed ones it absorbs, with coefficients
        (:attr:`~doe_calib.estimation.identifiability.Identifiability.absorbed`).

    Raises
    ------
    DataError
        No readings, or too few
        (:func:`~doe_calib.estimation.observation_count.check_count`).
    """
    params = model.nominal() if params is None else params
    where = measurements.source or "<measurements>"
    if len(measurements) == 0:
        raise DataError("no readings to identify from", where)
    tracked = ~measurements.contact
    if measurements.touch.any():
        check_planes(measurements, marker_points(model, measurements, params.values))
    if not tracked.any() and measurements.given_plane.any():
        params, reasons = fix_unseen_by_given_planes(model, measurements, params)
        params = fix_unseen_by_touches(model, measurements, params)
        for why in reasons:
            warnings.warn(why, IdentifiabilityWarning, stacklevel=3)
    elif not tracked.any():
        read = instruments(measurements)
        params = fix_unseen_by_contacts(model.robot, params, read)
        if "plane" in read:
            params = fix_unseen_by_touches(model, measurements, params)
        warnings.warn(unseen_words(read)[0], IdentifiabilityWarning, stacklevel=3)  # the report
        # groups the fixed parameters by these reasons: no note of its own
    elif _only_given(measurements) and _spread(given_sockets(measurements)) < 2:
        params = fix_unseen_by_given(model, measurements, params,
                                     register and params.free[params.index("base")].all())
    elif register and params.free[params.index("base")].all():
        params = register_base(model, measurements if tracked.all() else
                               measurements.subset(tracked), params)
    check_count(measurements, params)
    red = reduce_jacobian(model, measurements, params.values)
    params, notes, absorbed = fix_unidentifiable(model, measurements, params, reduction=red)
    turned = fix_base_turn(measurements, params)
    if turned is not params:
        params = turned
        told = [why for i, why in enumerate(params.fixed_reason) if i in params.index("base")]
        warnings.warn(next(w for w in told if w.startswith(_TURN_REASONS)),
                      IdentifiabilityWarning, stacklevel=3)
        absorbed = {k: v for k, v in absorbed.items() if params.free[params.position(k)]}
    return params, notes, red, absorbed
