"""Calibration of a TIAGo arm from real motion-capture data (four sessions, 2021).

Data: ``shared/data/tiago-mocap`` (see its README; not part of the project):
static postures of the torso lift (m) and the 7-joint arm (rad), and four
points of one rigid body tracked on the hand, in a frame fixed to the robot
base (m). Robot: ``tiago.urdf`` of the PyPI package example-robot-data (not a
project dependency). The study skips cleanly when either is missing.

What it does:

1. :func:`~.sessions.load_session` turns one wide file (one row = one posture, four
   points) into SI :class:`~doe_calib.io.measurements.Measurements`: markers ``P1..P4``,
   pose ids ``<session>:<row>``, σ per row = ``max(marker_std_mm, 0.1 mm)``.
2. :func:`rough_start` finds start values for the unknown marker positions in
   the flange frame and the base pose by alternation (nominal robot).
3. Models of increasing richness (``""`` = base + markers on the nominal URDF,
   ``joint_offset``, ``joint_offset+geometry``, and an exploratory gravity
   compliance) are judged by leave-one-session-out cross-validation, with one
   base frame shared by all sessions or one per session, and by 5-fold
   cross-validation over the distinct postures (the sessions repeat them).
4. The held-out residual of the best model is correlated with every joint,
   the time within the session, the marker jitter and gravity torques
   (:func:`correlations`); :func:`repeated_postures` checks the tracker frame
   across sessions without any model.
5. :func:`run` writes ``results/tiago_mocap.{md,json}`` and two PNGs.

Run: ``python -m studies.tiago_mocap [--data DIR] [--out results]``.
"""
from .drivers import repeated_postures
from .fitting import error_stats, errors_mm, fit
from .robot import (
                    COLUMNS,
                    DEFAULT_DATA,
                    JOINTS,
                    SIGMA_FLOOR_MM,
                    tiago_robot,
                    tiago_tool,
                    tiago_urdf,
)
from .sessions import load_session, read_sessions
from .start import rough_start
from .study import run

__all__ = ["COLUMNS", "DEFAULT_DATA", "JOINTS", "SIGMA_FLOOR_MM", "error_stats", "errors_mm", "fit",
           "load_session", "read_sessions", "repeated_postures", "rough_start", "run",
           "tiago_robot", "tiago_tool", "tiago_urdf"]
