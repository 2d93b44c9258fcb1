"""Gross outliers: single readings the rest of the data place far from where they were read.

A reading's deletion residual ``e_i = y_i − x_i(p̂₍ᵢ₎)`` is its misfit under the
fit to the *other* readings, which an outlier cannot pull. Under an adequate
model ``‖e_i / σ_i‖² ~ χ²(3)`` (leverage ignored: a few % at most), and the
largest of K is judged by Bonferroni: ``K · P(χ²₃ > t_i) < level``.

With σ estimated, σ̂ holds the outliers and any missing effect too. The
yardstick is then the noise *within* poses: a joint-space effect moves a
pose's markers rigidly, so what each pose's best small rigid motion
``e_j ≈ t + ω × x_j`` leaves (``3n − rank`` dof per pose) is noise, taken from
the poses without suspects. A single marker per pose has none: give σ.

Suspects are found by rounds: the readings beyond the threshold (the
:data:`MAX_OUTLIERS` worst when more are) are left out, the model refitted and
the threshold applied again, until the set settles. They are outliers only
when few (:data:`MAX_OUTLIERS`) and the other readings then fit within the
noise (:func:`~doe_calib.diagnosis.diagnose.diagnose`'s adequacy rules; with σ
estimated, the F test of the rest's rigid part against the within-pose part);
otherwise the effect tests judge.

A reading without coordinates has as deletion residual its misfit against its socket's
point, its ballbar's pivot or its plane as the other readings place it
(:mod:`~doe_calib.diagnosis.held_out_contacts`): an outlier left out no longer moves what
the rest are compared to. A plane touch or a ballbar length is one coordinate: χ²(1).
"""
from __future__ import annotations

from dataclasses import asdict, dataclass

import numpy as np
from scipy.special import fdtrc

from doe_calib.diagnosis.held_out_contacts import coordinates, held_out_errors
from doe_calib.estimation.chi_square import chi2_survival, chi2_upper_quantile
from doe_calib.estimation.identify import identify_quietly
from doe_calib.estimation.weighted_residuals import marker_points
from doe_calib.io.measurements import ESTIMATED

#: More suspects than this (readings) is not "a few outliers" but a model or σ problem.
MAX_OUTLIERS = 3
#: Rounds of leave-out-and-refit before the suspects must have settled.
MAX_ROUNDS = 4
#: Readings beyond the threshold in the fit to all: up to this many times
#: :data:`MAX_OUTLIERS` may be the outliers' pull on the fit (they are then left out worst
#: first); more are a model or σ problem.
SWAMPED = 10


@dataclass(frozen=True)
class Outlier:
    """One reading far from where the fit to the other readings puts it.

    Attributes
    ----------
    pose, marker : str
        Its pose id and marker.
    line : int
        Its line in ``source``, the file it was read from (0 when not from a file).
    source : str
    size_mm : float
        Length of its deletion residual, mm.
    size_sigma : float
        The same in σ: ``‖e_i‖ / σ_i`` with σ_i the reading's σ (the within-pose
        σ̂ when σ was estimated), dimensionless.
    p_value : float
        ``K · P(χ²_d > ‖e_i/σ_i‖²)`` (Bonferroni over the K readings; d its coordinates: 3,
        1 for a touch or a length), at most 1.
    n_readings : int
        K, the readings it was judged among.
    socket : str
        For a socket contact, its socket's id ("" otherwise).
    plane : str
        For a plane touch, its plane's id ("" otherwise).
    pivot : str
        For a ballbar length, its pivot's id ("" otherwise).
    """

    pose: str
    marker: str
    line: int
    source: str
    size_mm: float
    size_sigma: float
    p_value: float
    n_readings: int
    socket: str = ""
    plane: str = ""
    pivot: str = ""

    def words(self) -> str:
        """``pose 17, marker B (line 102 of m.csv): 1.5 mm = 50 σ off (p = 1e-300 …)``; a
        contact's says its socket (``marker ball in socket S2``), a touch its plane, a
        ballbar length its pivot (``marker ball from pivot P1``)."""
        where = (f" in socket {self.socket}" if self.socket else "") + \
            (f" on plane {self.plane}" if self.plane else "") + \
            (f" from pivot {self.pivot}" if self.pivot else "") + \
            (f" (line {self.line} of {self.source})" if self.line else "")
        p = f"p = {self.p_value:.2g}" if self.p_value >= 1e-300 else "p < 1e-300"
        return (f"pose {self.pose}, marker {self.marker}{where}: {self.size_mm:.3g} mm = "
                f"{self.size_sigma:.3g} σ from where the other readings put it ({p}, "
                f"Bonferroni over {self.n_readings} readings)")

    def to_dict(self) -> dict:
        return asdict(self)

    @classmethod
    def from_dict(cls, d: dict) -> "Outlier":
        return cls(**d)


def within_pose(error, predicted, config, rows) -> tuple:
    """Sum of squares and degrees of freedom of the residuals ``rows`` leave after each
    configuration's best small rigid motion (module notes).

    Parameters
    ----------
    error, predicted : ndarray, shape (K, 3)
        Residuals and modelled marker positions, m.
    config : ndarray of int, shape (K,)
        Configuration of each reading.
    rows : ndarray of bool, shape (K,)
        The readings to use; a configuration counts only with all its readings in.

    Returns
    -------
    (float, int)
        Sum of squares (m²) and its degrees of freedom (3n − rank per configuration).
    """
    ss, dof = 0.0, 0
    count = np.bincount(config)
    complete = np.bincount(config, rows) == count
    order = np.argsort(config, kind="stable")
    starts = np.r_[0, np.cumsum(count)]
    for n in np.unique(count[complete]):  # configurations of n readings, stacked
        group = np.flatnonzero(complete & (count == n))
        mine = order[starts[group][:, None] + np.arange(n)]           # (G, n)
        x = predicted[mine] - predicted[mine].mean(axis=1, keepdims=True)
        a, b, z = np.moveaxis(x, -1, 0)
        one, nil = np.ones_like(a), np.zeros_like(a)
        motion = np.stack([np.stack([one, nil, nil, nil, z, -b], -1),   # e_j = t + ω × x_j
                           np.stack([nil, one, nil, -z, nil, a], -1),
                           np.stack([nil, nil, one, b, -a, nil], -1)], 2)  # (G, n, 3, 6)
        motion = motion.reshape(len(group), 3 * n, 6)
        e = error[mine].reshape(len(group), 3 * n, 1)
        left = e - motion @ (np.linalg.pinv(motion, rcond=1e-9) @ e)
        ss += float(np.sum(left ** 2))
        dof += int(np.sum(3 * n - np.linalg.matrix_rank(motion, tol=None)))
    return ss, dof


def _fits(t, dof, sigma_m, level, tolerance, practical_um, survival) -> bool:
    """Diagnose's adequacy rules for a mean square ``t / dof`` against σ² (``survival``: p)."""
    ratio = np.sqrt(t / max(dof, 1))
    misfit_um = 1e6 * sigma_m * np.sqrt(max(ratio ** 2 - 1.0, 0.0))
    return survival >= level or ratio <= 1 + tolerance or misfit_um < practical_um


def _errors(model, measurements, values, out) -> tuple:
    """Reading minus model (K, 3), m, at ``values``, each reading without coordinates against
    its unknown as the readings not ``out`` place it (module notes), and the modelled points
    (K, 3)."""
    points = marker_points(model, measurements, values)
    return held_out_errors(measurements, ~out, points)[0], points


def _rest_fits_the_noise(error, sigma, keep, rank, level, tolerance, practical_um,
                         within=None, counted=None) -> bool:
    """Whether the readings ``keep`` fit within σ: their χ² against σ (given), or with
    ``within`` (the within-pose sum of squares and dof, σ estimated) the F test of the rest's
    rigid part against it. ``rank``: the parameters fitted, the sockets', pivots' and planes'
    unknowns included; ``counted``: each reading's coordinates (default 3)."""
    counted = np.full(len(keep), 3) if counted is None else counted
    if within is None:
        t = float(((error[keep] / sigma[keep, None]) ** 2).sum())
        dof = max(int(counted[keep].sum()) - rank, 1)
        return _fits(t, dof, float(np.median(sigma[keep])), level, tolerance, practical_um,
                     chi2_survival(t, dof))
    ss_in, dof_in = within
    dof = int(counted[keep].sum()) - rank - dof_in
    if dof <= 0:
        return True
    s2 = ss_in / dof_in
    t = (float((error[keep] ** 2).sum()) - ss_in) / s2
    return _fits(t, dof, np.sqrt(s2), level, tolerance, practical_um,
                 fdtrc(dof, dof_in, max(t / dof, 0.0)))  # a negative t: p = 1


def gross_outliers(model, measurements, fit, level: float = 0.01, tolerance: float = 0.05,
                   practical_um: float = 2.0) -> tuple:
    """The few readings that are gross outliers (module notes), largest first; () if none.

    Parameters
    ----------
    model : Model
    measurements : Measurements
        Readings with their σ settled (m); with ``sigma_source`` ``"estimated"`` the
        scale is the within-pose σ̂ of the poses without suspects (module notes).
    fit : IdentificationResult
        ``model`` fitted to every reading.
    level : float
        Bonferroni significance over the readings.
    tolerance, practical_um :
        With σ known, the other readings must fit within the noise by these
        rules (as :func:`~doe_calib.diagnosis.diagnose.diagnose`).

    Returns
    -------
    tuple of Outlier

    Examples
    --------
    >>> found = gross_outliers(model, measurements, fit)   # doctest: +SKIP
    >>> found[0].words()                                   # doctest: +SKIP
    'pose 17, marker B (line 102 of m.csv): 1.5 mm = 50 σ from where the other readings …'
    """
    if measurements.observed_per_configuration:  # a probe's virtual points are not readings
        return ()
    k = len(measurements)
    sigma, estimated = measurements.sigma, measurements.sigma_source == ESTIMATED
    counted = coordinates(measurements)
    # with the parameters, 3 per socket's point, pivot and plane
    rank = int(fit.parameters.free.sum()) + int(counted.sum()) - measurements.n_coordinates
    out, within = np.zeros(k, bool), None
    error, predicted = _errors(model, measurements, fit.parameters.values, out)
    critical = np.array([chi2_upper_quantile(min(level / k, 0.5), int(c))  # Bonferroni over K
                         for c in (1, 3)])[(counted == 3).astype(int)]
    for _ in range(MAX_ROUNDS):
        if estimated:  # the noise within poses, of the poses without suspects
            within = within_pose(error, predicted, measurements.config, ~out)
            if within[1] < 3:
                return ()
            scale = np.full(k, np.sqrt(within[0] / within[1]))
        else:
            scale = sigma
        t = ((error / scale[:, None]) ** 2).sum(axis=1)
        beyond = t > critical
        if np.array_equal(beyond, out):
            break
        if not 0 < beyond.sum() <= SWAMPED * MAX_OUTLIERS:
            return ()
        if beyond.sum() > MAX_OUTLIERS:  # a few outliers pull the fit: leave out the worst
            worst = np.zeros(k, bool)
            worst[np.argsort(t)[-MAX_OUTLIERS:]] = True
            if np.array_equal(worst, out):  # leaving them out does not clean the rest
                return ()
            beyond = worst
        out = beyond
        refit = identify_quietly(model, measurements.subset(~out), fit.parameters)
        error, predicted = _errors(model, measurements, refit.parameters.values, out)
    else:
        return ()
    if not out.any() or not _rest_fits_the_noise(error, sigma, ~out, rank, level, tolerance,
                                                 practical_um, within, counted):
        return ()
    cfg, names = measurements.configurations, model.tool.names
    found = [Outlier(cfg.pose[measurements.config[i]], names[measurements.marker[i]],
                     int(measurements.line[i]), str(measurements.source),
                     float(np.linalg.norm(error[i]) * 1e3),
                     float(np.linalg.norm(error[i]) / scale[i]),
                     float(min(chi2_survival(t[i], int(counted[i])) * k, 1.0)), k,
                     *_group_names(measurements, i))
             for i in np.flatnonzero(out)]
    return tuple(sorted(found, key=lambda o: -o.size_sigma))


def _group_names(measurements, i) -> tuple:
    """(socket id, plane id, pivot id) of reading ``i`` ("" where it has none): a ballbar
    length's socket is its pivot."""
    socket = measurements.socket_names[measurements.socket[i]] \
        if measurements.socket is not None and measurements.socket[i] >= 0 else ""
    plane = measurements.plane_names[measurements.plane[i]] if measurements.touch[i] else ""
    return ("", plane, socket) if measurements.ballbar[i] else (socket, plane, "")


#: What may have made an outlier of each kind of reading, in words.
CAUSES = {"point": "a reading off its target, a marker moved or swapped",
          "socket": "a ball not seated home in its socket (dirt, a slipped seat), a contact "
                    "written under another socket's id",
          "plane": "a touch off its plane (dirt, a burr, the probe triggered early), a touch "
                   "written under another plane's id",
          "pivot": "a ballbar not seated in its cups (dirt, a cup slipped, the bar lifted), a "
                   "length misread or mistyped, a length written under the wrong pivot's id"}


def causes(outliers) -> str:
    """What may have made ``outliers``, in one sentence: the causes of each kind of reading
    among them (:data:`CAUSES`), and a pose typed wrong."""
    kinds = {"socket" if o.socket else "plane" if o.plane else "pivot" if o.pivot else "point"
             for o in outliers}
    said = "; ".join(CAUSES[k] for k in CAUSES if k in kinds)
    return f"{said[0].upper()}{said[1:]}, or a pose typed wrong"


def outlier_verdict(outliers, adequacy_words: str) -> str:
    """A diagnosis verdict naming the outliers and what to do, no effect proposed.

    Parameters
    ----------
    outliers : sequence of Outlier
    adequacy_words : str
        The χ² test of every reading, in words (σ̂/σ, its interval, p).
    """
    one = len(outliers) == 1
    poses = list(dict.fromkeys(o.pose for o in outliers))
    head = "one reading is a gross error" if one else \
        f"{len(outliers)} readings are gross errors"
    listed = "; ".join(o.words() for o in outliers)
    python = "[" + ", ".join(repr(p) for p in poses) + "]"
    return (f"The model is NOT adequate ({adequacy_words}), but {head}, not an effect: {listed}. "
            f"{causes(outliers)}. "
            f"Re-measure {'that pose' if len(poses) == 1 else 'those poses'} or leave "
            f"{'it' if len(poses) == 1 else 'them'} out: rerun with --exclude-poses "
            f"{','.join(poses)} (each exclusion is reported; in Python "
            f"measurements.split_by_pose({python})[0]). No effect is tested until then: "
            f"an effect fitted to these readings would be fitted to the outlier.")
