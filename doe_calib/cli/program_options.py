"""Options that shape a written robot program: home, load-change pose, tool mass, trigger.

Shared by ``doe-calib export`` and ``doe-calib compensate --format``.
"""
from __future__ import annotations

from doe_calib.cli.common import parse_floats
from doe_calib.export import Payload, zero_home
from doe_calib.errors import OptionError
from doe_calib.export.stations import check_station, default_home


def program_arguments(c) -> None:
    """Add ``--home``, ``--load-change-pose``, ``--tool-mass`` and ``--trigger``."""
    c.add_argument("--home", default="auto", metavar="auto|zero|none|Q1,...,QN",
                   help="pose the program starts from and ends at: auto (default: the URDF's "
                        "zero clipped inside the joint limits if it is free of collisions, else "
                        "the design pose nearest to it), zero, none (start at the first pose and "
                        "end at the last), or joint values in deg (mm), e.g. "
                        "--home=0,-90,90,0,60,0")
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


def _pose(text: str, robot, option: str) -> tuple:
    values = parse_floats(text, robot.n_joints, f"{option} (deg, mm for prismatic joints)")
    return check_station(robot, values / robot.display_factors, option)


def stations(args, design, is_free=None) -> tuple:
    """``home`` and ``load_pose`` for :class:`doe_calib.export.Plan` from the options (SI).

    Returns
    -------
    dict
        Plan fields.
    str or None
        Which home ``auto`` chose, in words (None for the other choices).
    """
    robot, text, why = design.robot, args.home.strip().lower(), None
    if text == "auto":
        home, why = default_home(design, is_free)
    else:
        home = None if text == "none" else zero_home(robot) if text == "zero" else _pose(
            args.home, robot, "--home")
    load = None if args.load_change_pose is None else _pose(args.load_change_pose, robot,
                                                           "--load-change-pose")
    if load is not None and home is None:
        raise OptionError("--load-change-pose needs a home pose (not --home none)")
    return {"home": home, "load_pose": load}, why


def tool_payload(args) -> Payload:
    """The ``--tool-mass`` payload (no mass when not given)."""
    return Payload() if args.tool_mass is None else Payload.from_spec(args.tool_mass,
                                                                      "--tool-mass")
