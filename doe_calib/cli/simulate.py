"""``doe-calib simulate``: a simulated measurement campaign as a measurement CSV."""
from __future__ import annotations

import sys
from dataclasses import replace

from doe_calib.cli.common import (
    add_options,
    check_payloads,
    collision_arguments,
    collision_builder,
    effect_registry,
    load_robot_tool,
    parse_floats,
    parse_load,
    robot_arguments,
)
from doe_calib.cli.options import count, positive
from doe_calib.errors import DataError, OptionError
from doe_calib.io.json_file import strict_json

HELP = "simulate a measurement campaign"
EXAMPLE = ("doe-calib simulate --robot kr270.urdf --tool tool.yaml --poses 40 "
           "--load 250@0,0,200 --sigma 0.02 --seed 1 --out meas.csv --truth-out truth.json")


def add_arguments(c):
    robot_arguments(c)
    c.add_argument("--design", help="design of poses and loads: the JSON doe-calib design "
                                    "writes, or its CSV (else random poses); a contact design "
                                    "(design --sockets, --planes, --ballbar: its JSON) is "
                                    "simulated as --template simulates its CSV")
    c.add_argument("--template", metavar="CSV",
                   help="measurement CSV whose readings are simulated as they stand: its "
                        "poses, loads, markers, socket contacts, plane touches and ballbar "
                        "lengths (x, y, z unused, may be empty); a contact's or a touch's q "
                        "is written as the one that seats the true ball in its socket or on "
                        "its plane (IK on the truth from the row's q), the socket where the "
                        "truth puts the ball on average over its rows, the plane the best "
                        "through the truth's ball at its rows; a ballbar row keeps its q and "
                        "logs the true ball's distance from the pivot (the centre that best "
                        "fits the row's lengths on the truth, or its seated contacts' mean)")
    c.add_argument("--sockets", metavar="FILE",
                   help="with --template or a contact --design: the sockets of given position, "
                        "a socket plate's drawing (CSV socket,x,y,z[,socket_sigma], mm, the "
                        "frame of the readings, which --tracker places); the truth seats the "
                        "ball at each point moved by a draw of its socket_sigma (the plate as "
                        "made), the rows carry the drawing's x, y, z and socket_sigma")
    c.add_argument("--poses", type=count("--poses", 1, "pose"), default=30,
                   help="random poses when no design")
    c.add_argument("--constraints", metavar="CELL.yaml",
                   help="design constraints YAML (the cell: floor, boxes, joint limits, line "
                        "of sight): the random poses satisfy it and keep clear of collisions, "
                        "as design's candidates do")
    c.add_argument("--load", type=parse_load,
                   help="MASS_KG@X,Y,Z: measure each pose unloaded and with this mass (kg; "
                        "centre of mass in mm, flange frame); 0 kg measures unloaded only")
    c.add_argument("--sigma", type=positive("--sigma", "mm"), default=0.02,
                   help="noise σ per coordinate, mm (a socket contact's seating scatter per "
                        "axis, a touch's along its plane's normal, a ballbar length's)")
    c.add_argument("--truth", help="JSON with the true parameters (else random errors)")
    c.add_argument("--tracker", help="placement X,Y,Z,RX,RY,RZ (mm, rotation vector in deg) "
                                     "of the frame of the readings when errors are random: "
                                     "the tracker's, or the socket plate's (default: a few "
                                     "metres away at any angle; with sockets of given "
                                     "position, --sockets or x, y, z on a template's rows, "
                                     "within a few mm and 0.1° of the robot's base frame, "
                                     "as the design put the plate)")
    add_options(c, "--seed")
    c.add_argument("--out", required=True, help="measurement CSV to write")
    c.add_argument("--truth-out", help="JSON to write the true parameters to")
    c.add_argument("--json", action="store_true", help="print what was written as JSON "
                                                       "(messages go to stderr)")
    collision_arguments(c)   # used with --constraints


OUTPUTS = {"out": "file", "truth_out": "file"}
#: The std of a random socket plate's placement about the robot's base frame (m, rad).
PLATE_PLACEMENT = (2e-3, 1.7e-3)


def run(args):
    import numpy as np

    from doe_calib.estimation.result import load_parameters, save_parameters
    from doe_calib.io.csv_files import write_measurements
    from doe_calib.model.marker_model import build_model
    from doe_calib.model.seating import given_rows, simulate_readings
    from doe_calib.model.simulate import random_truth, simulate

    robot, tool = load_robot_tool(args)
    check_payloads(robot, [args.load] if args.load else [])
    model = build_model(robot, tool, args.model, registry=effect_registry(args))
    rng = np.random.default_rng(args.seed)
    template = _template(args, model)
    if args.truth:
        truth = load_parameters(args.truth, model)
    else:
        base = None
        if args.tracker:
            t = parse_floats(args.tracker, 6, "--tracker (mm, deg)")
            base = np.r_[t[:3] / 1000.0, np.radians(t[3:])]
        elif template is not None and given_rows(template).any():
            base = np.r_[rng.normal(0.0, PLATE_PLACEMENT[0], 3),
                         rng.normal(0.0, PLATE_PLACEMENT[1], 3)]
        truth = model.nominal().with_values(random_truth(model, rng, base=base))
    if template is not None:
        meas = simulate_readings(model, truth, template, args.sigma / 1000.0, rng,
                                 source=args.out)
    else:
        meas = simulate(model, truth, _configurations(args, model, truth, rng),
                        args.sigma / 1000.0, rng, source=args.out)
    cfg = meas.configurations
    write_measurements(args.out, meas, robot, tool)
    messages = sys.stderr if args.json else sys.stdout
    print(f"written: {args.out} ({len(meas)} readings, {len(cfg)} configurations, "
          f"σ = {args.sigma} mm{_without_coordinates(meas)})", file=messages)
    if args.truth_out:
        save_parameters(args.truth_out, truth, model.spec)
        print(f"written: {args.truth_out} (the true parameters)", file=messages)
    if args.json:
        print(strict_json({"measurements": args.out, "readings": len(meas),
                          "configurations": len(cfg), "poses": len(set(cfg.pose)),
                          "sigma_mm": args.sigma, "model": model.spec, "seed": args.seed,
                          "truth": args.truth_out}))


def _without_coordinates(meas) -> str:
    """The readings without coordinates of ``meas``, and the contacts in sockets of given
    position, in words ("" with none)."""
    import numpy as np

    from doe_calib.model.seating import given_rows

    def counted(n, one, many):
        return f"{n} {one if n == 1 else many}"

    bar, touch, given = meas.ballbar, meas.touch, given_rows(meas)
    seated = meas.contact & ~touch & ~bar
    said = []
    sockets = ("socket", "sockets")
    for rows, what, kind in ((seated, "socket contacts in {} of unknown position", sockets),
                             (given, "socket contacts in {} of given position", sockets),
                             (bar, "ballbar lengths from {}", ("pivot", "pivots"))):
        if rows.any():
            groups = counted(len(np.unique(meas.socket[rows])), *kind)
            said.append(f"{int(rows.sum())} " + what.format(groups))
    if touch.any():
        planes = counted(len(meas.planes_used), "plane", "planes")
        said.append(f"{int(touch.sum())} touches of {planes}")
    if (seated | given | touch).any():
        said.append("each q of a contact or touch the one seating the true ball")
    return "".join(f"; {s}" for s in said)


def _configurations(args, model, truth, rng):
    """The configurations to simulate: ``--design``'s, or ``--poses`` random ones (in the
    ``--constraints`` cell), each measured unloaded and with ``--load`` when given."""
    from doe_calib.io.csv_files import read_design
    from doe_calib.io.measurements import Configurations
    from doe_calib.model.loads import unloaded_and_loaded
    from doe_calib.model.simulate import random_configurations

    robot = model.robot
    if args.design:
        if args.load:
            raise OptionError("--load is for random poses: a --design carries its own loads")
        if args.constraints:
            raise OptionError("--constraints is for random poses: a --design's poses were "
                              "chosen inside its own")
        return read_design(args.design, robot)
    q = random_configurations(robot, args.poses, rng) if not args.constraints else \
        _poses_in_cell(args, model, truth, robot, model.tool, rng)
    if args.load:
        kg, com, _ = args.load
        return unloaded_and_loaded(model, truth.values, q, kg, com)
    return Configurations.from_arrays(q)


def _template(args, model):
    """The readings to simulate as they stand (:func:`~doe_calib.model.seating.
    simulate_readings`): ``--template``'s, or a contact ``--design``'s; with ``--sockets``
    given positions on their sockets' rows; None: configurations to simulate."""
    from doe_calib.cli.export_contacts import contact_design
    from doe_calib.io.csv_files import read_measurements

    design = contact_design(args.design) if args.design else None
    if args.template:
        for given, name in ((args.design, "--design"), (args.load, "--load"),
                            (args.constraints, "--constraints")):
            if given:
                raise OptionError(f"{name} is not taken with --template: the template's rows "
                                  f"are the poses, loads and readings simulated")
        template = read_measurements(args.template, model.robot, model.tool,
                                     require_xyz=False)
    elif design is not None:
        for given, name in ((args.load, "--load"), (args.constraints, "--constraints")):
            if given:
                raise OptionError(f"{name} is not taken with a contact design: its contacts "
                                  f"are the readings simulated")
        template = design.readings(model, args.sigma / 1000.0)
    elif args.sockets:
        raise OptionError("--sockets gives the positions of a template's sockets: give "
                          "--template or a contact --design")
    else:
        return None
    return _with_given_sockets(template, args.sockets) if args.sockets else template


def _with_given_sockets(template, path):
    """``template`` whose contacts in the sockets of the file ``path`` carry their given
    position (x, y, z) and ``socket_sigma``, m.

    Raises
    ------
    DataError
        A socket of the file no row of the template is seated in; a ``socket_sigma`` not a
        number, or negative (the file, line and column named).
    """
    import numpy as np

    from doe_calib.design.candidates.sockets import read_sockets

    sockets = read_sockets(path)
    tolerance = _socket_sigmas(path, sockets.names)
    seated = template.contact & ~template.ballbar & ~template.touch
    names = template.socket_names
    xyz = template.xyz.copy()
    drawn = np.zeros(len(template)) if template.socket_sigma is None else \
        template.socket_sigma.copy()
    for name, point, sigma in zip(sockets.names, sockets.points, tolerance):
        at = seated & (template.socket == names.index(name)) if name in names else \
            np.zeros(len(template), bool)
        if not at.any():
            raise DataError(f"socket {name!r}: no contact of the template is seated in it "
                            f"(its sockets: {', '.join(names) or 'none'})", path)
        xyz[at], drawn[at] = point, sigma
    return replace(template, xyz=xyz, socket_sigma=drawn if np.any(drawn > 0) else None)


def _socket_sigmas(path, names) -> list:
    """Each socket's ``socket_sigma`` (m) in the sockets file ``path`` (0 without the
    column or with an empty cell)."""
    import numpy as np

    from doe_calib.io.named_rows import read_named_rows

    _, v, lines = read_named_rows(path, "socket", ("x", "y", "z"), ["socket_sigma"])
    sigma = np.nan_to_num(v["socket_sigma"], nan=0.0)
    for value, line in zip(sigma, lines):
        if value < 0.0:
            raise DataError(f"socket_sigma '{value:g}': a position's std is a number of mm, 0 "
                            f"or more", path, line, "socket_sigma")
    return (sigma / 1000.0).tolist()


def _poses_in_cell(args, model, truth, robot, tool, rng):
    """``--poses`` random poses (m, N), rad/m, that satisfy the ``--constraints`` cell and keep
    clear of collisions (unless ``--no-collision``), drawn as design draws its candidates."""
    from doe_calib.design import LoadCase, read_constraints
    from doe_calib.design.candidates.draw import feasible_candidates
    from doe_calib.design.candidates.feasibility import build_feasibility

    constraints = read_constraints(args.constraints, robot, tool)
    loads = [LoadCase(kg, com, r) for kg, com, r in [args.load] if kg > 0] if args.load else []
    build = collision_builder(args, robot, tool, constraints)
    feasibility = build_feasibility(model, truth.values, constraints, loads)
    return feasible_candidates(feasibility, robot, args.poses, rng,
                               None if build is None else build(loads)).q
