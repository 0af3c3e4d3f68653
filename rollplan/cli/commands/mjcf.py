"""``rollplan mjcf``: the robot's MuJoCo model (MJCF)."""

from __future__ import annotations

from dataclasses import replace

from ...errors import InputError
from ...robot import default_robot, load_robot
from ..arguments import number
from ..common import EXIT_OK, check_outputs
from ..format import num


def cmd_mjcf(args) -> int:
    from ...execution import mujoco_engine as engine
    from ...outputs import write_atomic

    check_outputs(json=args.out, inputs=[args.robot])
    robot = load_robot(args.robot) if args.robot else default_robot()
    settings = d = engine.DEFAULT_SETTINGS
    step = d.timestep if args.timestep is None else args.timestep
    # one option at a time (the time step first, with the default contact time constant of at least two of its
    # steps), so that a refusal names the option
    for flag, fields in (("--timestep", {"timestep": step, "solref": (max(d.solref[0], 2.0 * step), d.solref[1])}),
                         ("--floor-solref", {"solref": d.solref if args.floor_solref is None else
                                             tuple(args.floor_solref)}),
                         ("--friction", {"friction": d.friction if args.friction is None else args.friction}),
                         ("--rolling-resistance", {"rolling": args.rolling_resistance}),
                         ("--com-offset", {"com_offset": tuple(args.com_offset)})):
        if flag == "--floor-solref" and args.floor_solref is None:
            continue
        try:
            settings = replace(settings, **fields)
        except InputError as exc:
            raise InputError(f"{flag}: {exc}") from None
    try:
        xml = engine.mjcf(robot, settings)
    except InputError as exc:   # the settings hold; the offset is bounded by the robot's radius
        raise InputError(f"--com-offset: {exc}") from None
    model = engine.compile_model(xml)
    mass, com, inertia = engine.composite_inertia(model)
    R = robot.radius
    j_zz = inertia[2, 2]
    print(f"rollplan mjcf: robot k = {num(robot.k)} (14), Jzz = {num(robot.j_zz)} kg m^2, "
          f"M = {num(robot.mass_total)} kg")
    print(f"  MuJoCo        composite about the centre: diag {num(inertia[0, 0])} {num(inertia[1, 1])} {num(j_zz)} "
          f"kg m^2, M = {num(mass)} kg, centre of mass {num(com[0])} {num(com[1])} {num(com[2])} m, "
          f"k = {num((j_zz + mass * R * R) / j_zz)}")
    print(f"  contact       solref {num(settings.solref[0])} s {num(settings.solref[1])}, friction "
          f"{num(settings.friction)}, rolling resistance {num(settings.rolling)} m; RK4 at {num(settings.timestep)} s")
    write_atomic(args.out, xml.encode(), "MJCF model")
    print(f"wrote {args.out}")
    return EXIT_OK


def register(sub) -> None:
    """The ``mjcf`` command's options."""
    j = sub.add_parser("mjcf", help="write the robot's MuJoCo model (MJCF): shell, two rotors, torque motors, floor")
    j.add_argument("--robot", metavar="FILE.toml", help="robot file (default: the shipped default robot)")
    j.add_argument("--out", required=True, metavar="FILE.xml", help="output MJCF file")
    j.add_argument("--com-offset", type=number, nargs=3, default=[0.0, 0.0, 0.0], metavar=("DX", "DY", "DZ"),
                   help="centre of mass off the centre, in the shell's frame [m], shorter than R/2 (default 0 0 0)")
    j.add_argument("--floor-solref", type=number, nargs=2, default=None, metavar=("TIMECONST", "DAMPRATIO"),
                   help="the contact's spring-damper: time constant [s] in [2 timesteps, 10], and damping ratio in "
                        "[0.01, 100] (default 0.0002 1, stiff: two RK4 steps, or 2 DT with --timestep)")
    j.add_argument("--rolling-resistance", type=number, default=0.0, metavar="MU",
                   help="rolling friction [m] in [0, 1] (default 0: none)")
    j.add_argument("--friction", type=number, default=None, metavar="MU",
                   help="sliding friction coefficient in [0.001, 1000] (default 2)")
    j.add_argument("--timestep", type=number, default=None, metavar="DT",
                   help="RK4 step [s] in [1e-6, 0.01] (default 1e-4)")
    j.set_defaults(func=cmd_mjcf)
