"""Marker positions an identification result predicts, with their std (validation, CLI)."""
from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from doe_calib.errors import DataError, ModelError
from doe_calib.io.measurements import Configurations, Measurements, provisional
from doe_calib.estimation.labelled import read_only
from doe_calib.estimation.measured_region import outside_joints
from doe_calib.estimation.session import error_mm, reregister, session_notes
from doe_calib.estimation.sockets import frame_unseen_part, frame_words, from_contacts
from doe_calib.estimation.unseen import measured_markers, unseen_notes, unseen_part
from doe_calib.model.evaluation import observation_matrix


@dataclass(frozen=True, eq=False)
class Prediction:
    """Predicted marker positions of readings, tracker frame; its arrays are read-only.

    Attributes
    ----------
    xyz : ndarray, shape (K, 3)
        Predicted position of each reading's marker, m.
    std : ndarray, shape (K, 3)
        Its std per coordinate from the parameter covariance, σ̂-scaled (unless
        predicted ``apriori``), m.
    config, marker : ndarray of int, shape (K,)
        Configuration and marker index of each reading.
    marker_names : tuple of str
    registration : Reregistration or None
        What was re-fitted on the readings before predicting
        (``register="frame"`` or ``"frame+tool"``), with the error before and after.
    notes : tuple of str
        Numerical findings in words, e.g. an error far beyond the predicted
        std that a re-registration would remove (naming ``--register``).
    """

    xyz: np.ndarray
    std: np.ndarray
    config: np.ndarray
    marker: np.ndarray
    marker_names: tuple
    registration: object = None
    notes: tuple = field(default=())

    def __post_init__(self):
        for name in ("xyz", "std", "config", "marker"):
            object.__setattr__(self, name, read_only(getattr(self, name), None))

    @property
    def xyz_mm(self) -> np.ndarray:
        return self.xyz * 1000.0

    @property
    def std_mm(self) -> np.ndarray:
        return self.std * 1000.0

    def __len__(self) -> int:
        return len(self.xyz)

    def residuals(self, measurements) -> np.ndarray:
        """Measured minus predicted position of each reading, shape (K, 3), m.

        Raises
        ------
        DataError
            ``measurements`` are not the readings predicted, or have no x, y, z.
        """
        if (len(measurements) != len(self) or not np.array_equal(measurements.config, self.config)
                or not np.array_equal(measurements.marker, self.marker)):
            raise DataError(f"these {len(measurements)} readings are not the {len(self)} the "
                            "prediction was made for; predict them first")
        if not np.all(np.isfinite(measurements.xyz)):
            raise DataError("the readings have no measured x, y, z to compare with")
        return measurements.xyz - self.xyz

    def error(self, measurements) -> dict:
        """RMS per coordinate, 3-D RMS, mean and max 3-D error against ``measurements``, mm."""
        return error_mm(self.residuals(measurements))

    def rms_3d(self, measurements) -> float:
        """3-D RMS error against ``measurements``, m."""
        return self.error(measurements)["rms_3d_mm"] / 1000.0


def result_model(result, registry=None):
    """Build the model a result was identified with (CasADi), with its parameters in order.

    Parameters
    ----------
    result : IdentificationResult
    registry : EffectRegistry, optional
        The effects the model string may name (default the built-in ones); a
        user effect needs a registry holding its file
        (``DEFAULT_REGISTRY.with_file(path)``).

    Returns
    -------
    (Model, ParameterSet)
        The model and the result's parameters in the model's order.

    Raises
    ------
    ModelError
        The model names an effect the registry does not hold (the message
        names the effect and the file it came from), or its parameters are
        not the result's.
    """
    from doe_calib.model.effects import DEFAULT_REGISTRY, split_model
    from doe_calib.model.marker_model import build_model

    registry = DEFAULT_REGISTRY if registry is None else registry
    missing = [w.split("(")[0].strip() for w in split_model(result.model)
               if w.split("(")[0].strip() not in registry]
    if missing:
        files = {n: result.effect_files.get(n) for n in missing}
        where = "; ".join(f"effect {n!r}" + (f" from file {f}" if f else "")
                          for n, f in files.items())
        raise ModelError(f"predicting needs the model {result.model!r}, and its {where} is not "
                         "in the registry: give the effect file (--effect-file FILE, or "
                         "registry=DEFAULT_REGISTRY.with_file(FILE))")
    model = build_model(result.robot, result.tool, result.model, registry=registry)
    return model, aligned_parameters(model, result)


def aligned_parameters(model, result):
    """The result's parameters in ``model``'s order (they are, unless the model changed).

    Raises
    ------
    ModelError
        ``model`` lacks some of the result's parameters.
    """
    if model.nominal().names == result.parameters.names:
        return result.parameters
    try:
        return model.nominal().from_list(result.parameters.to_list())
    except KeyError as exc:
        raise ModelError(f"the model {model.spec!r} does not have the result's parameters "
                         f"({exc.args[0]}); was its effect file changed?") from None


def predict(result, data, model=None, *, registry=None, apriori: bool = False,
            register: str | None = None, tolerance: dict | None = None) -> Prediction:
    """Marker positions ``result`` predicts for readings or configurations.

    Parameters
    ----------
    result : IdentificationResult
    data : Measurements or Configurations
        Readings (their configurations and markers are predicted), or
        configurations (every marker at every configuration, in that order).
    model : Model, optional
        The model ``result`` was identified with; built from the result when
        not given (:func:`result_model`).
    registry : EffectRegistry, optional
        Names the model's effects when it is built here (a user effect's file).
    apriori : bool
        The covariance for the a-priori σ (what ``doe-calib predict`` writes);
        default: scaled by (σ̂/σ)².
    register : {None, "frame", "frame+tool"}
        Re-fit the tracker frame (the 6 base parameters), or also the tool
        mounting (the marker positions), on the readings before predicting,
        every robot parameter held at the result's value
        (:func:`~doe_calib.estimation.session.reregister`): a new session
        whose tracker moved or whose probe was remounted. Needs readings with
        x, y, z.
    tolerance : dict, optional
        Stated prior std (SI) of the parameters the readings could not separate,
        by name, ``block:unit`` or unit (:func:`~doe_calib.estimation.unseen.tolerances`;
        default each one's scale, 1 mm, 1 mrad, which the notes say is not the user's).

    Returns
    -------
    Prediction
        Positions (m) and their std ``√diag(B Σ Bᵀ + G S Gᵀ)`` with ``B`` the
        observation matrix of each reading, Σ the covariance of the free
        parameters and ``G S Gᵀ`` what the calibration's readings could not see
        (:mod:`~doe_calib.estimation.unseen`: ~0 for a marker they measured, the
        tool file's tolerance for one they never did); ``notes`` says so where it
        dominates. After a fit to socket contacts alone, positions and std are
        relative to the sockets' frame (:mod:`~doe_calib.estimation.sockets`): the
        first note says what the contacts could not see (where the robot stands, the
        scale with its stated tolerance per metre), which the std leaves out. When the
        readings have x, y, z and the error is far beyond that std, ``notes`` says
        whether a re-registration removes it.

    Raises
    ------
    DataError
        ``register`` without readings (or without x, y, z).
    """
    if isinstance(data, Measurements):
        cfg, config, marker = data.configurations, data.config, data.marker
    elif isinstance(data, Configurations):
        cfg, n = data, len(result.tool.names)
        config = np.repeat(np.arange(len(cfg)), n)
        marker = np.tile(np.arange(n), len(cfg))
    else:
        raise DataError(f"predict takes Measurements or Configurations, not "
                        f"{type(data).__name__}")
    if model is None:
        model, params = result_model(result, registry)
    else:
        params = aligned_parameters(model, result)
    measured = isinstance(data, Measurements) and bool(np.all(np.isfinite(data.xyz)))
    if measured:  # a re-registration weighs readings without σ alike
        data = provisional(data)
    done = None
    if register is not None:
        if not measured:
            raise DataError(f"register={register!r} re-fits the tracker frame on measured "
                            "readings: give readings with x, y, z")
        done = reregister(model, params, data, register)
        params = params.with_values(done.parameters.values)
    x, b = observation_matrix(model, params.values, cfg)
    bf = b[config, marker][..., params.free]
    cov = np.asarray(result.cov_params(apriori=apriori))
    var = np.einsum("kif,fg,kig->ki", bf, cov, bf)
    frame, contacts = frame_words(params, tolerance), from_contacts(result)
    part = (frame_unseen_part if contacts else unseen_part)(
        model, params, measured_markers(result), tolerance, within=result.joint_range)
    notes = (f"the std is {frame}",) if frame else ()
    if len(part):
        _, b_bare = observation_matrix(model, params.values, type(cfg).from_arrays(
            cfg.q, None, cfg.env))
        effect = part.effect(b[config, marker], b_bare[config, marker])
        notes = notes + unseen_notes(effect, np.sqrt(np.sum(var, 1)), marker,
                                     result.tool.names, part, params)
        var = var + np.sum(effect ** 2, axis=-1)
    std = np.sqrt(np.clip(var, 0.0, None))
    outside = [f"{p} ({w})" for p, w in
               zip(cfg.pose, outside_joints(result.robot, cfg.q, result.joint_range)) if w]
    if outside:
        notes = notes + (f"{len(outside)} configuration(s) outside the joint range the "
                         f"calibration measured: {'; '.join(outside)}; their std extrapolates "
                         f"the model, and an effect it lacks may grow there",)
    if measured:
        sigma = result.sigma_mm * result.sigma_ratio / 1000.0
        expected = float(np.sqrt(sigma ** 2 + np.mean(std ** 2)))
        notes = notes + session_notes(model, params, data, expected, done)
    return Prediction(x[config, marker], std, np.asarray(config), np.asarray(marker),
                      tuple(result.tool.names), done, notes)
