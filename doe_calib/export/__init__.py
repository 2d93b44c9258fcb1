"""Robot programs that visit a design's poses: KUKA KRL, ABB RAPID, URScript, a joint program
for any robot (CSV, ROS 2 JointTrajectory YAML), and the plain pose list (design CSV).

Each pose is visited once per load case in the order of a :class:`.sequence.Plan`
(:func:`.program.moves`), limits re-checked; the program stops for the operator where
the load changes, declares the payload and waits for the measurement at each pose
(:class:`.program.Settings`). :func:`.safety.check_program` checks and routes the moves;
:func:`.cycle.cycle_time` estimates how long the program runs.
"""
from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path
from typing import Callable

import numpy as np

from doe_calib.errors import DataError, OptionError
from doe_calib.export import dialects, joint_program
from doe_calib.export.axis_map import AxisMap
from doe_calib.export.cycle import CycleTime, cycle_time
from doe_calib.export.payload import Payload
from doe_calib.export.program import Move, Settings, Waypoint, moves, realised_approach
from doe_calib.export.safety import Collision, ProgramCheck, check_program, program_models
from doe_calib.export.sequence import Plan
from doe_calib.export.stations import zero_home
from doe_calib.io.csv_files import write_design
from doe_calib.io.measurements import Configurations


@dataclass(frozen=True)
class Format:
    """An export format: its file suffixes and ``render(design, visits, settings)`` → suffix →
    file text (None: the pose list, a design CSV, :func:`program_configurations`, which
    moves nothing and is not checked); ``language``: the :func:`.dialects.six_axes`
    language of a program for 6 axes only (None: any robot); ``controller``: whether it
    takes the controller's joint values (an axis map)."""

    description: str
    suffixes: tuple
    render: Callable | None
    language: str | None = None
    controller: bool = True

    def check_robot(self, robot) -> None:
        """Raise :class:`~doe_calib.errors.ModelError` for a robot this format cannot drive."""
        if self.language is not None:
            dialects.six_axes(robot, self.language)


#: Format name → Format.
FORMATS = {
    "krl": Format("KUKA KRL .src/.dat", (".src", ".dat"), dialects.krl, "KRL"),
    "rapid": Format("ABB RAPID module", (".mod",), dialects.rapid, "RAPID"),
    "urscript": Format("Universal Robots URScript", (".script",), dialects.urscript,
                       "URScript"),
    "csv": Format("joint program for any robot: home, via points, load-change stops, "
                  "triggers, checked", (".csv",), joint_program.csv_program),
    "ros2": Format("ROS 2 trajectory_msgs/JointTrajectory YAML of the checked program",
                   (".yaml",), joint_program.ros2_trajectory, controller=False),
    "poses": Format("pose list: the design CSV (docs/formats.md section 4) in the program's "
                    "order, unchecked", (".csv",), None, controller=False),
}


def program_configurations(design, visits) -> Configurations:
    """The measured configurations in the program's order, with its joint values (turns
    chosen) and the approach directions it realises (what the ``backlash`` effect reads)."""
    cfg = design.configurations
    visits = list(visits)
    measured = [m for m in visits if m.measures]
    rows = [m.row for m in measured]
    q = np.array([m.urdf_q for m in measured]).reshape(len(rows), design.robot.n_joints)
    return Configurations.from_arrays(q, cfg.wrench[rows], cfg.temperature[rows],
                                      [m.pose for m in measured],
                                      realised_approach(visits, design.robot))


def export_design(design, fmt: str, out, name: str = "doe_calib", dwell: float = 3.0,
                  handshake: int | None = None, plan: Plan | None = None,
                  visits=None, trigger: str | None = None,
                  tool: Payload | None = None, load_change_time: float = 300.0) -> list[Path]:
    """Write ``design`` as a robot program (or pose list); return the files written.

    Parameters
    ----------
    design : DesignResult
    fmt : {"krl", "rapid", "urscript", "csv", "ros2", "poses"}
    out : path-like
        A directory (files ``name`` + suffix) or a file path, whose stem is then the
        program name (KRL needs file and program names to match).
    dwell, handshake, trigger, tool, load_change_time
        As :class:`.program.Settings` (dwell and load_change_time in s; tool default:
        mass 0).
    plan : Plan, optional
        Grouping, order, pre-poses, stations and axis map (the CSV keeps URDF values).
    visits : sequence of Move, optional
        The visits made with ``plan``, e.g. routed by :func:`.safety.check_program`;
        default ``moves(design, plan)``.

    Raises
    ------
    DataError
        A pose outside the joint limits, a demanded side a pre-pose cannot realise, or a
        bad program name.
    ModelError
        A robot the format cannot drive (6 axes).
    OptionError
        A negative dwell, a handshake not an I/O number ≥ 1, a trigger not one line of
        ASCII, or an axis map with a format of URDF values (ros2, poses).

    Examples
    --------
    >>> export_design(design, "krl", "programs/", name="calib")  # doctest: +SKIP
    [PosixPath('programs/calib.src'), PosixPath('programs/calib.dat')]
    """
    if fmt not in FORMATS:
        raise DataError(f"unknown export format {fmt!r}; formats: {', '.join(FORMATS)}")
    if not dwell >= 0:
        raise OptionError(f"the dwell (--dwell) must be 0 s or more, got {dwell} s")
    if handshake is not None and not (float(handshake).is_integer() and handshake >= 1):
        raise OptionError(f"the handshake (--handshake) must be a digital I/O number of 1 or "
                          f"more, got {handshake}")
    out = Path(out)  # a path with a suffix names the file
    stem, name = (out.with_suffix(""), out.stem) if out.suffix else (out / name, name)
    form = FORMATS[fmt]
    form.check_robot(design.robot)
    if not form.controller and plan is not None and plan.axis_map is not None:
        raise OptionError(f"--axis-map: the {fmt} format keeps the URDF's joint values; the "
                          f"axis map is for the controllers' programs (krl, rapid, urscript, "
                          f"csv)")
    visits = moves(design, plan) if visits is None else list(visits)
    if form.render is None:
        stem.parent.mkdir(parents=True, exist_ok=True)
        write_design(stem.with_suffix(".csv"), program_configurations(design, visits),
                     design.robot)
        return [stem.with_suffix(".csv")]
    texts = form.render(design, visits, Settings(name, dwell, handshake, trigger,
                                                 Payload() if tool is None else tool,
                                                 load_change_time))
    stem.parent.mkdir(parents=True, exist_ok=True)
    paths = [stem.with_suffix(s) for s in form.suffixes]
    for path in paths:
        path.write_text(texts[path.suffix], encoding="ascii")
    return paths


__all__ = ["FORMATS", "AxisMap", "Collision", "CycleTime", "Format", "Move", "Payload", "Plan",
           "ProgramCheck", "Settings", "Waypoint", "check_program", "cycle_time",
           "export_design", "moves", "program_configurations", "program_models",
           "realised_approach", "zero_home"]
