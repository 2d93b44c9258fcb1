"""Robot programs that visit a design's poses: KUKA KRL, ABB RAPID, URScript, and the design CSV.

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
from doe_calib.export import dialects
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
    file text (None: the design CSV, :func:`program_configurations`)."""

    description: str
    suffixes: tuple
    render: Callable | None


#: Format name → Format.
FORMATS = {
    "krl": Format("KUKA KRL .src/.dat", (".src", ".dat"), dialects.krl),
    "rapid": Format("ABB RAPID module", (".mod",), dialects.rapid),
    "urscript": Format("Universal Robots URScript", (".script",), dialects.urscript),
    "csv": Format("design CSV (docs/formats.md section 4)", (".csv",), None),
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
                  tool: Payload | None = None) -> list[Path]:
    """Write ``design`` as a robot program (or design CSV); return the files written.

    Parameters
    ----------
    design : DesignResult
    fmt : {"krl", "rapid", "urscript", "csv"}
    out : path-like
        A directory (files ``name`` + suffix) or a file path, whose stem is then the
        program name (KRL needs file and program names to match).
    dwell, handshake, trigger, tool
        As :class:`.program.Settings` (dwell in s; tool default: mass 0).
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
        ASCII, or an axis map with the design CSV.

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
    if form.render is None and plan is not None and plan.axis_map is not None:
        raise OptionError("--axis-map: the design CSV keeps the URDF's joint values; the axis "
                          "map is for robot programs (krl, rapid, urscript)")
    visits = moves(design, plan) if visits is None else list(visits)
    if form.render is None:
        stem.parent.mkdir(parents=True, exist_ok=True)
        write_design(stem.with_suffix(".csv"), program_configurations(design, visits),
                     design.robot)
        return [stem.with_suffix(".csv")]
    texts = form.render(design, visits, Settings(name, dwell, handshake, trigger,
                                                 Payload() if tool is None else tool))
    stem.parent.mkdir(parents=True, exist_ok=True)
    paths = [stem.with_suffix(s) for s in form.suffixes]
    for path in paths:
        path.write_text(texts[path.suffix], encoding="ascii")
    return paths


__all__ = ["FORMATS", "AxisMap", "Collision", "CycleTime", "Format", "Move", "Payload", "Plan",
           "ProgramCheck", "Settings", "Waypoint", "check_program", "cycle_time",
           "export_design", "moves", "program_configurations", "program_models",
           "realised_approach", "zero_home"]
