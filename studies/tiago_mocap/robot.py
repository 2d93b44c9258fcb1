"""The TIAGo of the study: URDF from example-robot-data, flange, the tracked body's four points."""
from __future__ import annotations

import argparse
from pathlib import Path

from doe_calib import Robot, Tool

DEFAULT_DATA = Path(__file__).resolve().parents[3] / "shared" / "data" / "tiago-mocap"
JOINTS = ("torso_lift_joint",) + tuple(f"arm_{i}_joint" for i in range(1, 8))
POINTS = ("P1", "P2", "P3", "P4")
#: The tracked body sits on the hand; hand_palm_link is rigidly fixed to arm_7_link
#: (66.6 mm along its axis). Any link fixed to arm_7 gives the same kinematic
#: model (the marker positions are free, expressed in this frame); only the
#: exploratory gravity load is applied at this frame's origin.
FLANGE = "hand_palm_link"
SIGMA_FLOOR_MM = 0.1
URDF_IN_PACKAGE = "robots/tiago_description/robots/tiago.urdf"
COLUMNS = tuple(f"{a}{j}" for j in range(1, 5) for a in "xyz") + JOINTS + (
    "t_start_robot", "marker_std_mm")


def tiago_urdf() -> Path | None:
    """Path of ``tiago.urdf`` in the installed example-robot-data, or None when absent.

    Version 6 of the PyPI package ships the files without the Python module
    ``example_robot_data``; the file is then found through the package metadata.
    """
    try:
        import example_robot_data
        base = Path(example_robot_data.getModelPath(URDF_IN_PACKAGE.split("/", 1)[1]))
        for path in (base / URDF_IN_PACKAGE.split("/", 1)[1], base / URDF_IN_PACKAGE):
            if path.is_file():
                return path
    except Exception:  # noqa: BLE001 - any failure means: look elsewhere
        pass
    from importlib import metadata
    try:
        files = metadata.distribution("example-robot-data").files or []
    except metadata.PackageNotFoundError:
        return None
    for f in files:
        if str(f).endswith(URDF_IN_PACKAGE):
            path = Path(f.locate()).resolve()
            return path if path.is_file() else None
    return None


def missing(data_dir) -> str | None:
    """Why a TIAGo study cannot run here (no data folder, no URDF), or None when it can."""
    if not Path(data_dir).is_dir():
        return f"no data folder {data_dir}"
    if tiago_urdf() is None:
        return "the TIAGo URDF needs `pip install example-robot-data`"
    return None


def session_study_parser(name: str) -> argparse.ArgumentParser:
    """The command line of a study on the session CSVs: ``--data DIR`` and ``--out DIR``."""
    ap = argparse.ArgumentParser(prog=f"python -m studies.{name}")
    ap.add_argument("--data", type=Path, default=DEFAULT_DATA / "csv",
                    help="folder of the session CSVs in the measurement format")
    ap.add_argument("--out", type=Path, default=Path("results"), help="output folder")
    return ap


def skipped(name: str, data_dir) -> bool:
    """True, having said why, when the study ``name`` cannot run here (:func:`missing`)."""
    why = missing(data_dir)
    if why:
        print(f"{name}: skipped: {why}")
    return why is not None


def tiago_robot(urdf=None) -> Robot:
    """Torso lift + 7 arm joints from the URDF root to :data:`FLANGE`."""
    robot = Robot.from_urdf(urdf or tiago_urdf(), flange=FLANGE)
    if tuple(robot.joint_names) != JOINTS:
        raise RuntimeError(f"unexpected chain {robot.joint_names}; expected {JOINTS}")
    return robot


def tiago_tool() -> Tool:
    """The four tracked points, nominal at the flange origin (unknown; see :func:`rough_start`)."""
    return Tool.from_markers({p: [0.0, 0.0, 0.0] for p in POINTS}, flange=FLANGE)
