"""Fit statistics of an identification: χ², dof, p, σ̂/σ with its interval, evaluations."""
from __future__ import annotations

import re
from dataclasses import dataclass

import numpy as np

from doe_calib.estimation.chi_square import chi2_quantile, chi2_survival
from doe_calib.estimation.observation_count import COUNTED
from doe_calib.estimation.sockets import is_socket_note

#: Level of the σ̂/σ interval.
RATIO_LEVEL = 0.95
#: The χ² test rejects a fit clearly below this p-value with σ̂/σ above this ratio
#: (:func:`misfit_finding`): a misfit beyond doubt and beyond a σ a few % optimistic.
CLEAR_REJECTION_P, CLEAR_REJECTION_RATIO = 1e-3, 1.2


@dataclass(frozen=True)
class FitStatistics:
    """How well the model fits, with the a-priori σ (lmfit's and statsmodels' header).

    Attributes
    ----------
    readings : int
        Marker readings, every kind (socket contacts, plane touches, ballbar lengths
        included).
    observations : int
        Scalar observations: 3 per reading of a point (a tracker's reading or a socket
        contact), 1 per plane touch or ballbar length, less 3 per socket, plane or pivot
        of unknown position (its point is estimated with the fit: formats.md §3).
    free, fixed : int
        Parameters estimated and held.
    chi2 : float
        ‖r_w‖², the squared norm of the residuals weighted by the a-priori σ
        (equal to ``dof`` by construction when σ was estimated).
    dof : int
        Degrees of freedom: observations − free.
    p_value : float
        P(χ²_dof ≥ χ²): small when the residuals are larger than σ explains.
        NaN when σ was estimated (the test is then not informative).
    sigma_ratio : float
        σ̂/σ = √(χ²/dof) (1 when σ was estimated).
    sigma_ratio_interval : tuple of float
        95 % interval of the true σ over σ (over σ̂ when σ was estimated),
        from the χ²_dof distribution.
    sigma_source : str
        ``given``, ``per reading`` or ``estimated``.
    jacobian_evaluations, residual_evaluations, iterations : int or None
        Work of the estimator (None when it did not say); an iteration of
        Levenberg–Marquardt is one Jacobian evaluation.
    converged : bool
    message : str
        The solver's words.
    sockets : int
        Sockets of unknown position among the readings (0 without contacts), ballbar pivots
        not counted.
    contacts, touches, lengths : int
        Socket contacts (in sockets of unknown position), plane touches and ballbar lengths
        among the readings.
    planes, pivots : int
        Planes touched and ballbar pivots, each of unknown position.
    """

    readings: int
    observations: int
    free: int
    fixed: int
    chi2: float
    dof: int
    p_value: float
    sigma_ratio: float
    sigma_ratio_interval: tuple
    sigma_source: str
    jacobian_evaluations: int | None
    residual_evaluations: int | None
    iterations: int | None
    converged: bool
    message: str
    sockets: int = 0
    contacts: int = 0
    touches: int = 0
    lengths: int = 0
    planes: int = 0
    pivots: int = 0

    @property
    def reduced_chi2(self) -> float:
        """χ²/dof = (σ̂/σ)²."""
        return self.chi2 / self.dof if self.dof > 0 else float("nan")

    @property
    def chi2_informative(self) -> bool:
        """False when σ was estimated from these residuals (χ² = dof by construction)."""
        return self.sigma_source != "estimated"

    def lines(self) -> list[str]:
        """The statistics as ``name = value`` lines, for reports."""
        lo, hi = self.sigma_ratio_interval
        kinds = self.kinds()
        out = [f"readings               = {self.readings}" + (f" ({kinds})" if kinds else ""),
               self._observations(),
               f"free parameters        = {self.free}",
               f"fixed parameters       = {self.fixed}",
               f"degrees of freedom     = {self.dof}"]
        if self.chi2_informative:
            out += [f"chi-square ‖r_w‖²      = {self.chi2:.6g}",
                    f"reduced chi-square     = {self.reduced_chi2:.6g}",
                    f"p-value P(χ² ≥ ‖r_w‖²) = {self.p_value:.3g}",
                    f"σ̂/σ                   = {self.sigma_ratio:.4g}  "
                    f"({100 * RATIO_LEVEL:g} % interval of σ_true/σ: {lo:.4g} … {hi:.4g})"]
        else:
            out += ["chi-square test        = not informative: σ was estimated from these "
                    "residuals (σ̂ = √(‖r‖²/dof))",
                    f"σ_true/σ̂ interval      = {lo:.4g} … {hi:.4g} ({100 * RATIO_LEVEL:g} %)"]
        out += [f"σ source               = {self.sigma_source}"]
        work = [f"{n} {v}" for n, v in (("iterations", self.iterations),
                                        ("residual evaluations", self.residual_evaluations))
                if v is not None]
        if work:
            out.append(f"work                   = {', '.join(work)}")
        out.append(f"converged              = {'yes' if self.converged else 'NO'}: "
                   f"{self.message}")
        return out

    def kinds(self) -> str:
        """The readings by kind (``20 points read, 20 plane touches``) when any has no
        coordinates; '' otherwise."""
        points = self.readings - self.contacts - self.touches - self.lengths
        kinds = [_count(n, what) for n, what in ((points, "point(s) read"),
                                                 (self.contacts, "socket contact(s)"),
                                                 (self.touches, "plane touch(es)"),
                                                 (self.lengths, "ballbar length(s)")) if n]
        return ", ".join(kinds) if points != self.readings else ""

    def observations_words(self) -> tuple:
        """(``observations (T − 3P)``, ``P = 3 planes of unknown position``): the
        observations as a formula of the readings' kinds, and each of its letters that is not
        all the readings ('' when none); ``observations`` alone when they are not counted so
        (6 per pose of a 6-DoF probe)."""
        k = self.readings - self.touches - self.lengths
        terms = [(k, "3K", f"K = {_count(k, 'reading(s)')} of three coordinates"),
                 (self.touches, "T", f"T = {_count(self.touches, 'plane touch(es)')}"),
                 (self.lengths, "L", f"L = {_count(self.lengths, 'ballbar length(s)')}")]
        less = [(n, f"3{letter}", f"{letter} = {_count(n, what)} of unknown position")
                for n, letter, what in ((self.sockets, "S", "socket(s)"),
                                        (self.planes, "P", "plane(s)"),
                                        (self.pivots, "V", "ballbar pivot(s)"))]
        if 3 * k + self.touches + self.lengths - \
                3 * (self.sockets + self.planes + self.pivots) != self.observations:
            return "observations", ""  # counted per pose (a 6-DoF probe's)
        added = [t for t in terms if t[0]]
        formula = " + ".join(t[1] for t in added) + "".join(f" − {t[1]}" for t in less if t[0])
        said = [t[2] for t in added if t[0] != self.readings] + [t[2] for t in less if t[0]]
        return f"observations ({formula})", ", ".join(said)

    def _observations(self) -> str:
        name, legend = self.observations_words()
        return f"{name:<22} = {self.observations}" + (f" ({legend})" if legend else "")

    def summary(self) -> str:
        """The statistics as text, one ``name = value`` line each."""
        return "\n".join(self.lines())

    __str__ = summary

    def _repr_pretty_(self, printer, cycle) -> None:
        """What IPython and Jupyter show: the summary, not the dataclass's fields."""
        printer.text(self.summary())


def _count(n: int, what: str) -> str:
    """``1 plane touch``, ``3 plane touches``: ``what`` with its plural's ending in brackets
    (``plane touch(es)``, ``point(s) read``)."""
    return f"{n} " + re.sub(r"[(](\w+)[)]", r"\1" if n != 1 else "", what)


def misfit_finding(stats: FitStatistics, sigma_mm: float) -> str | None:
    """A finding when the χ² test rejects the fit clearly, else None.

    Clearly: p < :data:`CLEAR_REJECTION_P` and σ̂/σ > :data:`CLEAR_REJECTION_RATIO`.
    Never when σ was estimated from the fit's own residuals (the test is then not
    informative, ``p_value`` NaN).

    Parameters
    ----------
    stats : FitStatistics
    sigma_mm : float
        The a-priori σ per coordinate, mm.

    Examples
    --------
    >>> stats = FitStatistics(120, 360, 33, 30, 1336.5, 327, 5.8e-122, 2.02, (1.88, 2.19),
    ...                       "given", 5, 5, 5, True, "")
    >>> misfit_finding(stats, 0.02)[:60]
    'the χ² test rejects this fit (p = 5.8e-122, σ̂/σ = 2.02: σ̂ ='
    """
    if not (stats.p_value < CLEAR_REJECTION_P and stats.sigma_ratio > CLEAR_REJECTION_RATIO):
        return None
    r = stats.sigma_ratio
    return (f"the χ² test rejects this fit (p = {stats.p_value:.2g}, σ̂/σ = {r:.3g}: σ̂ = "
            f"{r * sigma_mm:.3g} mm for σ = {sigma_mm:.3g} mm, {stats.sigma_source}): the "
            f"residual is larger than the noise explains: an effect the model lacks (a cyclic "
            f"error, a compliance, backlash), a σ too small, or a unit mistake; run "
            f"doe-calib diagnose to find which")


def ratio_interval(chi2: float, dof: int, level: float = RATIO_LEVEL) -> tuple:
    """Interval of σ_true/σ from ‖r_w‖² ~ (σ_true/σ)² χ²_dof, two-sided at ``level``."""
    if dof <= 0 or not np.isfinite(chi2):
        return (float("nan"), float("nan"))
    a = (1 - level) / 2
    return (float(np.sqrt(chi2 / chi2_quantile(1 - a, dof))),
            float(np.sqrt(chi2 / chi2_quantile(a, dof))))


def fit_statistics(result) -> FitStatistics:
    """The :class:`FitStatistics` of an identification result.

    χ² is ``(σ̂/σ)²·dof`` with dof = observations − free (3K, less 3 per socket of
    unknown position, or 6 per pose of a 6-DoF probe), as ``σ̂/σ`` was computed from
    ‖r_w‖² (:func:`~doe_calib.estimation.assembly.finish`).
    """
    p, conv = result.parameters, result.convergence
    n_free = int(p.free.sum())
    dof = int(result.n_observations - n_free)
    estimated = result.sigma_source == "estimated"
    chi2 = float(result.sigma_ratio ** 2 * dof) if dof > 0 else float("nan")
    p_value = chi2_survival(chi2, dof) if dof > 0 and not estimated else float("nan")

    def count(key):
        v = conv.get(key)
        return None if v is None else int(v)

    residuals = getattr(result, "residuals", {})
    counts = residuals.get("counts", {})
    readings = int(residuals.get("n", result.n_observations // 3))
    if not counts and any(is_socket_note(w) for w in getattr(result, "warnings", ())):
        counts = {"sockets": max(readings - result.n_observations // 3, 0)}  # a result
        # written before the counts were kept: sockets were the only readings without x, y, z
    return FitStatistics(
        readings=readings, observations=int(result.n_observations),
        free=n_free, fixed=len(p) - n_free, chi2=chi2, dof=dof, p_value=p_value,
        sigma_ratio=float(result.sigma_ratio), sigma_ratio_interval=ratio_interval(chi2, dof),
        sigma_source=result.sigma_source, jacobian_evaluations=count("iterations"),
        residual_evaluations=count("evaluations"), iterations=count("iterations"),
        converged=bool(conv.get("converged", False)), message=str(conv.get("message", "")),
        **{k: int(counts.get(k, 0)) for k in COUNTED})
