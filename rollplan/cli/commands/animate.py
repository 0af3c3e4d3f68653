"""``rollplan animate``: the sphere rolling under a plan's rotor rates (GIF)."""

from __future__ import annotations

from ...errors import InputError
from ...progress import Progress
from ..arguments import whole
from ..common import EXIT_OK, check_outputs


def cmd_animate(args) -> int:
    from ...execution.plants import simulate_rotors
    from ...io import load_rotor_plan
    from ...plots.animation import make_animation

    check_outputs(json=args.out, inputs=[args.plan_file])
    if not args.out.lower().endswith(".gif"):
        raise InputError(f"--out {args.out!r} is not allowed: animate writes a GIF; give a name ending in .gif")
    if not 2 <= args.frames <= 2000:
        raise InputError(f"--frames {args.frames} is not allowed: it must lie in [2, 2000]")
    if not 1 <= args.fps <= 100:
        raise InputError(f"--fps {args.fps} is not allowed: it must lie in [1, 100]")
    rp = load_rotor_plan(args.plan_file)
    keep = rp.distinct
    sim = simulate_rotors(rp.robot, rp.time[keep], rp.rotor_rates[keep], rp.goal, x0=rp.start.array())
    with Progress(unit="frames") as progress:
        make_animation(rp.time[keep], sim.state, rp.rotor_rates[keep], rp.robot, rp.goal, args.out, args.frames,
                       args.fps, progress=progress)
    print(f"wrote {args.out}")
    return EXIT_OK


def register(sub) -> None:
    """The ``animate`` command's options."""
    a = sub.add_parser("animate", help="animate the sphere rolling under the plan's rotor rates (GIF)")
    a.add_argument("plan_file", metavar="PLAN.json", help="made by: rollplan plan ... --duration T --json FILE")
    a.add_argument("--out", metavar="FILE.gif", required=True, help="output animation (GIF)")
    a.add_argument("--frames", type=whole, default=100, help="number of frames in [2, 2000] (default 100)")
    a.add_argument("--fps", type=whole, default=20, help="frames per second in [1, 100] (default 20)")
    a.set_defaults(func=cmd_animate)
