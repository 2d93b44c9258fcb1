"""Options that shape a written robot program: home, load-change pose, tool mass, trigger.

Shared by ``doe-calib export`` and ``doe-calib compensate --format``.
"""
from __future__ import annotations

from typing import TYPE_CHECKING

from doe_calib.cli.common import parse_floats
from doe_calib.errors import OptionError

if TYPE_CHECKING:
    from doe_calib.export import Payload


def program_arguments(c, home: str = "auto") -> None:
    """Add ``--home`` (default ``home``), ``--load-change-pose``, ``--tool-mass``, ``--trigger``."""
    c.add_argument("--home", default=home, metavar="auto|zero|none|Q1,...,QN",
                   help="pose the program starts from and ends at: auto (the URDF's zero "
                        "clipped inside the joint limits if it is free of collisions, else the "
                        "design pose nearest to it), zero, none (start at the first pose and end "
                        "at the last), or joint values in deg (mm), e.g. --home=0,-90,90,0,60,0 "
                        f"(default {home})")
    c.add_argument("--load-change-pose", metavar="Q1,...,QN",
                   help="pose at which the operator changes the load, deg (mm); default: the "
                        "home pose")
    c.add_argument("--tool-mass", metavar="KG@X,Y,Z",
                   help="the tool's own mass and centre of mass (mm, flange frame), declared "
                        "as the payload at the start and added to each load; default 0")
    c.add_argument("--trigger", metavar="LINE",
                   help="one line of the program's language written at every measurement pose "
                        "after the dwell, e.g. \"set_digital_out(2, True)\" (URScript), "
                        "\"$OUT[7]=TRUE\" (KRL), \"PulseDO doTrigger;\" (RAPID)")


def _pose(text: str, robot, option: str, limits) -> tuple:
    from doe_calib.export.stations import check_station

    values = parse_floats(text, robot.n_joints, f"{option} (deg, mm for prismatic joints)")
    return check_station(robot, values / robot.display_factors, option, limits)


def stations(args, design, is_free=None, limits=None) -> tuple:
    """``home``, ``load_pose`` and ``limits`` for :class:`doe_calib.export.Plan` (SI).

    ``is_free(q)``: whether a pose is free of collisions (None: not checked);
    ``limits``: (lower, upper), rad (m), a cell file's joint limits (None: the
    URDF's).

    Returns
    -------
    dict
        Plan fields.
    str or None
        Which home ``auto`` chose, in words (None for the other choices).
    """
    from doe_calib.export import zero_home
    from doe_calib.export.stations import default_home

    robot, text, why = design.robot, args.home.strip().lower(), None
    if text == "auto":
        home, why = default_home(design, is_free, limits)
    else:
        home = None if text == "none" else zero_home(robot, limits) if text == "zero" else \
            _pose(args.home, robot, "--home", limits)
    load = None if args.load_change_pose is None else _pose(args.load_change_pose, robot,
                                                           "--load-change-pose", limits)
    if load is not None and home is None:
        raise OptionError("--load-change-pose needs a home pose (not --home none)")
    return {"home": home, "load_pose": load, "limits": limits}, why


def tool_payload(args) -> Payload:
    """The ``--tool-mass`` payload (no mass when not given)."""
    from doe_calib.export import Payload

    return Payload() if args.tool_mass is None else Payload.from_spec(args.tool_mass,
                                                                      "--tool-mass")
