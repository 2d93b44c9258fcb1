"""What several commands share: robot/tool arguments, number and load parsing, warnings."""
from __future__ import annotations

import sys
from typing import TYPE_CHECKING

from doe_calib.cli.choices import DEFAULT_CLEARANCE, DEFAULT_MODEL, DEFAULT_SELF_CLEARANCE
from doe_calib.cli.options import at_least, count, positive
from doe_calib.errors import OptionError

if TYPE_CHECKING:
    import numpy as np


def model_option(text: str) -> str:
    """``--model``: a model string; ``none`` is the empty model (base and markers only)."""
    if text.strip().lower() == "none":
        return ""
    if not text.strip():
        raise OptionError(f"--model is empty: name the effects joined by '+' (e.g. "
                          f"{DEFAULT_MODEL}) or write --model none for base and markers only")
    return text


#: ``--approach-sign``: the file's approach convention (formats.md §3) or its reverse.
APPROACH_SIGNS = ("as-read", "reversed")

#: Options several commands declare alike, declared once: option → ``add_argument`` keywords.
SHARED = {
    "--robot": dict(required=True, help="URDF file of the nominal robot"),
    "--flange": dict(help="flange link (default: the tool file's, else the chain's last link)"),
    "--model": dict(default=DEFAULT_MODEL, type=model_option,
                    help=f"effects joined by '+' (default {DEFAULT_MODEL}); 'none' for base and "
                         f"markers only"),
    # results, and models naming a user effect, need its file
    "--effect-file": dict(action="append", metavar="FILE.py",
                          help="Python file declaring a user effect "
                               "(doe_calib.model.effects.user); repeat for several"),
    "--data": dict(required=True, nargs="+", metavar="CSV",
                   help="measurement CSV(s) (docs/formats.md); several files are several "
                        "sessions (a 'session' column also says so)"),
    "--skip-bad": dict(action="store_true", help="drop bad rows, reporting each"),
    # a diagnosis proposes reversed when backlash fits negative
    "--approach-sign": dict(choices=APPROACH_SIGNS, default=APPROACH_SIGNS[0],
                            help="reversed: negate every approach direction read or derived "
                                 "from the row order (a file whose convention is the reverse: "
                                 "backlash by approach then fits positive); default as-read"),
    "--result": dict(required=True, help="identification result JSON"),
    "--task-point": dict(default="0,0,0", help="X,Y,Z of the task point in the flange frame, "
                                               "mm (default the flange)"),
    "--seed": dict(type=count("--seed", 0), help="random seed"),
}


def add_options(c, *names) -> None:
    """Add the :data:`SHARED` options ``names`` to the command parser ``c``, in order."""
    for name in names:
        c.add_argument(name, **SHARED[name])


def robot_arguments(c, tool_required: bool = True):
    """Add ``--robot``, ``--flange``, ``--tool``, ``--model`` and ``--effect-file``.

    ``tool_required`` False: the command can also read 6-DoF probe files
    (``--angles``), whose tool comes from the data; :func:`load_robot_tool`
    then asks for ``--tool`` when it is needed.
    """
    add_options(c, "--robot", "--flange")
    c.add_argument("--tool", required=tool_required,
                   help="tool YAML with marker positions (mm): 1 reflector, 2 or more markers"
                        + ("" if tool_required else "; not with --angles (6-DoF probe files)"))
    add_options(c, "--model", "--effect-file")


def effect_registry(args):
    """The effects ``--model`` and result files may name: the catalogue plus the
    ``--effect-file`` effects (a new :class:`~doe_calib.model.effects.EffectRegistry`)."""
    from doe_calib.model.effects import registry_with_files

    return registry_with_files(getattr(args, "effect_file", None))


def load_robot_tool(args):
    """The Robot and Tool named by ``--robot``, ``--tool`` and ``--flange``."""
    from doe_calib.model.robot import Robot
    from doe_calib.model.tool import Tool

    if args.tool is None:
        raise OptionError("--tool is needed: the tool YAML with the marker positions (mm); "
                          "for 6-DoF probe files give --angles instead")
    tool = Tool.from_yaml(args.tool)
    robot = Robot.from_urdf(args.robot, flange=args.flange or tool.flange)
    return robot, tool


def read_data(paths, robot, tool, sigma=None, skip_bad=False, require_xyz=True,
              approach_sign: str = APPROACH_SIGNS[0]):
    """Measurements of one or several files (sessions), with what was dropped or doubted on stderr.

    ``sigma`` (m): σ of the readings without their own (:func:`sigma_option`).
    Rows dropped on request are reported one line each; joint readings a hair
    past a limit (accepted) are summarised. ``approach_sign`` ``"reversed"``
    negates every approach direction (said on stderr).
    """
    from doe_calib.io.csv_files import read_measurements
    from doe_calib.io.measurements import concatenate

    meas = concatenate([read_measurements(p, robot, tool, sigma=sigma, skip_bad=skip_bad,
                                          require_xyz=require_xyz) for p in paths])
    for msg in meas.dropped:
        print(f"dropped: {msg}", file=sys.stderr)
    for msg in meas.warnings[:3]:
        print(f"warning: {msg}", file=sys.stderr)
    if len(meas.warnings) > 3:
        print(f"warning: … and {len(meas.warnings) - 3} more joint readings slightly past a "
              f"limit (accepted as measured)", file=sys.stderr)
    if approach_sign == APPROACH_SIGNS[1]:
        print("approach directions reversed at your request (--approach-sign reversed)",
              file=sys.stderr)
        meas = meas.with_approach_reversed()
    return meas


def excluding(meas, poses: str | None):
    """The measurements without the poses named in ``--exclude-poses``, each reported on stderr."""
    import numpy as np

    if not poses:
        return meas
    names = [p.strip() for p in poses.split(",") if p.strip()]
    known = set(meas.configurations.pose)
    unknown = [p for p in names if p not in known]
    if unknown:
        raise OptionError(f"--exclude-poses: no pose {unknown[0]!r} in the data")
    kept, held = meas.split_by_pose(names)
    pose = np.array([held.configurations.pose[c] for c in held.config])
    for p in names:
        lines = held.line[pose == p]
        print(f"excluded at your request: pose {p} ({len(lines)} readings, lines "
              f"{lines.min()}–{lines.max()})", file=sys.stderr)
    return kept


def stage_progress():
    """A one-line ``note (done/total)`` display on a terminal (stderr), following the progress
    protocol (:mod:`doe_calib.runtime.progress`); None (silent) otherwise."""
    if not sys.stderr.isatty():
        return None

    def show(done, total, note):
        count = "" if total is None else f" ({done}/{total})"
        print(f"\r{note}{count}"[:100].ljust(100), end="", file=sys.stderr, flush=True)
    return show


def model_and_measurements(args, estimate_sigma: bool = True, registry=None):
    """The model (``--model``) and the measurements (``--data``, ``--sigma``, ``--skip-bad``,
    ``--exclude-poses``, ``--approach-sign``).

    With no σ given (no ``--sigma``, no ``sigma`` column) and ``estimate_sigma``,
    σ is settled by :func:`~doe_calib.estimation.sigma.resolve_sigma` (the σ̂ of the starting
    model), said on stderr.
    ``registry`` names the effects ``--model`` may use (default :func:`effect_registry`).
    """
    from doe_calib.estimation.sigma import resolve_sigma
    from doe_calib.model.marker_model import build_model

    robot, tool = load_robot_tool(args)
    registry = effect_registry(args) if registry is None else registry
    model = build_model(robot, tool, args.model, registry=registry)
    meas = read_data(args.data, robot, tool, sigma_option(args), args.skip_bad,
                     approach_sign=args.approach_sign)
    meas = excluding(meas, getattr(args, "exclude_poses", None))
    if estimate_sigma and meas.sigma_estimated:
        settled = resolve_sigma(model, meas)
        print(settled.words, file=sys.stderr)
        meas = settled.measurements
    return model, meas


def sigma_option(args) -> float | None:
    """``--sigma``, given in mm (the unit of the users' files), in metres (the Python API's)."""
    return None if getattr(args, "sigma", None) is None else args.sigma / 1000.0


def parse_floats(text: str, n: int, what: str) -> np.ndarray:
    """``n`` comma-separated finite numbers, or an :class:`OptionError` naming ``what``."""
    import numpy as np

    try:
        vals = np.array([float(v) for v in text.split(",")])
    except ValueError:
        raise OptionError(f"{what}: expected {n} comma-separated numbers, got {text!r}") from None
    if len(vals) != n:
        raise OptionError(f"{what}: expected {n} comma-separated numbers, got {len(vals)}")
    if not np.all(np.isfinite(vals)):
        raise OptionError(f"{what}: expected {n} finite numbers, got {text!r}")
    return vals


#: Heaviest load accepted by ``--load``, kg (a heavy-duty robot carries up to ~2 300 kg).
MAX_LOAD_KG = 10000.0


def parse_load(text: str):
    """``MASS_KG@X,Y,Z[:R]`` (centre of mass in mm, flange frame; radius in mm) → (kg, m, m).

    The mass is 0 … :data:`MAX_LOAD_KG` kg: a negative mass would pull the
    flange up, a larger one is a typing error (grams?). ``R`` is the radius
    of the sphere the load is drawn as in the collision check (None: a steel
    sphere of that mass).
    """
    mass, _, where = text.partition("@")
    where, _, size = where.partition(":")
    try:
        kg = float(mass)
    except ValueError:
        raise OptionError(f"--load {text!r}: expected MASS_KG@X,Y,Z, e.g. 250@0,0,200") from None
    if not 0.0 <= kg <= MAX_LOAD_KG:
        raise OptionError(f"--load {text!r}: the mass must be 0 to {MAX_LOAD_KG:.0f} kg, got "
                          f"{kg:g} kg (a mass hung on the flange, in kg)")
    com = parse_floats(where or "0,0,0", 3, "--load centre of mass (mm)") / 1000.0
    radius = None
    if size:
        radius = float(parse_floats(size, 1, "--load radius after ':' (mm)")[0]) / 1000.0
        if radius <= 0:
            raise OptionError(f"--load {text!r}: the radius after ':' must be positive (mm)")
    return kg, com, radius


def check_payloads(robot, loads) -> None:
    """Refuse a ``--load`` far beyond the URDF's effort limits, with the numbers.

    Parameters
    ----------
    robot : Robot
    loads : sequence of (kg, com (3,) m, radius) as :func:`parse_load` returns them

    Raises
    ------
    OptionError
        :func:`~doe_calib.model.loads.payload_beyond_effort` found a joint
        that cannot hold the payload in most poses.
    """
    from doe_calib.model.loads import payload_beyond_effort

    for kg, com, _ in loads:
        why = payload_beyond_effort(robot, kg, com)
        if why:
            raise OptionError(f"--load {kg:g}@{','.join(f'{1000 * c:g}' for c in com)}: {why}")


def fix_and_free(params, fix: str | None, free: str | None):
    """``params`` with the ``--fix`` names fixed, then the ``--free`` names freed.

    Each option is a comma-separated list of parameter or block names; an
    unknown name is an :class:`OptionError` naming the option and the closest names.
    """
    for option, text in (("--fix", fix), ("--free", free)):
        if text is None:
            continue
        names = [n.strip() for n in text.split(",")]
        if not all(names):
            raise OptionError(f"{option} {text!r}: an empty name; write comma-separated "
                              f"parameter or block names, e.g. {option} geometry,dq_a1")
        try:
            params = params.fixed(names) if option == "--fix" else params.freed(names)
        except OptionError as exc:
            raise OptionError(f"{option}: {exc}") from None
    return params


def show_result(args, result, *written) -> None:
    """Print ``result``'s summary (its JSON with ``--json``), then the files ``written``
    on stderr."""
    from doe_calib.io.json_file import strict_json

    print(strict_json(result.to_dict()) if args.json else result.summary())
    print(f"\nwritten: {', '.join(map(str, written))}", file=sys.stderr)


def report_warnings(caught):
    """Print recorded warnings to stderr, one line each."""
    for w in caught:
        print(f"warning: {w.message}", file=sys.stderr)


def collision_arguments(c, defaults_from: str | None = None):
    """Add ``--clearance``, ``--self-clearance``, ``--srdf``, ``--package-dir``, ``--no-collision``.

    ``defaults_from``: what the clearances default to when not given (e.g.
    ``"the design's"``); None: the collision model's defaults.
    """
    clear, self_clear = 1000.0 * DEFAULT_CLEARANCE, 1000.0 * DEFAULT_SELF_CLEARANCE
    said = f"{defaults_from}, else " if defaults_from else ""
    c.add_argument("--clearance", type=at_least("--clearance", 0.0, "mm"),
                   default=None if defaults_from else clear, metavar="MM",
                   help=f"distance the robot keeps from the tool, payloads, floor and keep-out "
                        f"boxes, mm (default {said}{clear:g}; 0: no contact)")
    c.add_argument("--self-clearance", type=at_least("--self-clearance", 0.0, "mm"),
                   default=None if defaults_from else self_clear, metavar="MM",
                   help=f"distance the robot's links keep from one another, mm "
                        f"(default {said}{self_clear:g})")
    c.add_argument("--move-clearance", type=at_least("--move-clearance", 0.0, "mm"),
                   metavar="MM",
                   help=f"distance kept from tool, payloads and cell along the moves between "
                        f"poses, at most --clearance, mm (default {said}half the clearance: a "
                        f"pose on the boundary of its clearance can always be left)")
    c.add_argument("--move-self-clearance", type=at_least("--move-self-clearance", 0.0, "mm"),
                   metavar="MM",
                   help=f"distance the robot's links keep from one another along the moves, mm "
                        f"(default {said}half the self-clearance)")
    c.add_argument("--planner-checks", type=count("--planner-checks", 1), default=5000,
                   metavar="N",
                   help="work budget of one search of the motion planner (OMPL RRT-Connect) "
                        "for a move that no straight line or simple route clears: state "
                        "checks (default 5000; a search near the move, then one over the "
                        "whole joint range); the same budget gives the same path on any "
                        "machine")
    c.add_argument("--planner-time", type=positive("--planner-time", "s"), default=30.0,
                   metavar="S",
                   help="safety net: wall time after which a search of the motion planner "
                        "ends whatever its budget, s (default 30, never reached on a working "
                        "machine; a search it ends depends on the machine's speed)")
    c.add_argument("--planner-seed", type=count("--planner-seed", 0), default=0, metavar="N",
                   help="seed of the motion planner's sampling (default 0: the same path on "
                        "every run)")
    c.add_argument("--no-planner", action="store_true",
                   help="do not plan moves: a move no simple route clears collides")
    c.add_argument("--srdf", help="SRDF whose <disable_collisions> pairs are not checked "
                                  "(default: adjacent links and pairs always in contact)")
    c.add_argument("--package-dir", action="append", metavar="DIR",
                   help="folder holding the packages of the URDF's package:// meshes (repeat "
                        "for several; ROS_PACKAGE_PATH and the URDF's own folders are searched "
                        "too)")
    c.add_argument("--no-collision", action="store_true",
                   help="skip the collision check (not recommended)")


def collision_builder(args, robot, tool, constraints, recorded: dict | None = None):
    """``build(loads)`` → the collision model the options ask for; None with ``--no-collision``.

    Parameters
    ----------
    recorded : dict, optional
        A design's ``constraints["collision"]`` (``clearance_mm``,
        ``self_clearance_mm``): the clearances when the options give none.
    """
    from doe_calib.collision import PlannerSettings, build_collision_model

    if args.no_collision:
        return None
    recorded = recorded or {}
    metres = {}
    for name, default in (("clearance", DEFAULT_CLEARANCE),
                          ("self_clearance", DEFAULT_SELF_CLEARANCE)):
        pose, move = getattr(args, name), getattr(args, f"move_{name}")
        # a move clearance not given follows a pose clearance given, else the design's, else half
        if move is None and pose is None:
            move = recorded.get(f"move_{name}_mm")
        if pose is None:
            pose = recorded.get(f"{name}_mm", 1000.0 * default)
        metres[name] = pose / 1000.0
        metres[f"move_{name}"] = None if move is None else move / 1000.0
    planner = None if args.no_planner else PlannerSettings(
        time=args.planner_time, seed=args.planner_seed, checks=args.planner_checks)

    def build(loads):
        return build_collision_model(robot, tool, loads, constraints, srdf=args.srdf,
                                     planner=planner, package_dirs=args.package_dir or (),
                                     **metres)
    return build
