"""rollplan: exact, dynamically realizable motion planning for a spherical robot driven by two
internal rotors.

It implements, on one symbolic CasADi model, the geometric-phase planner of

    M. Svinin, A. Morinaga and M. Yamamoto, "On the Geometric Phase Approach to Motion Planning for a
    Spherical Rolling Robot in Dynamic Formulation"

(cited in full once, here; everywhere else "the paper" and its equation numbers), and a
direct-collocation optimal-control planner for the same :class:`Problem`.
"""

from . import interrupts as _interrupts

# Started as the `rollplan` command (or `python -m rollplan.cli`): Ctrl-C while the modules load (a second or
# two, casadi and matplotlib) exits 130 with one line instead of an import traceback, until rollplan.cli.main
# takes over (rollplan.interrupts.guard_start_up); imported by a program, nothing changes.
_GUARDED = _interrupts.guard_start_up()

from .core.curves import A_MAX, Curve, Piece, circle_point, figure_eight  # noqa: E402
from .errors import InputError, NoPlanError, SolverError  # noqa: E402
from .execution.actuation import Motion, actuate  # noqa: E402
from .execution.plants import Simulation, simulate_rotors  # noqa: E402
from .planners import METHODS, solve  # noqa: E402
from .planners.collocation import CollocationPlanner, CollocationResult, collocate  # noqa: E402
from .planners.geometric import (  # noqa: E402
    LEGS,
    SOLVERS,
    ComposedPlan,
    ComposedPlanner,
    GeometricPhasePlanner,
    Plan,
    Route,
    StepResult,
    as_composed,
    plan,
    plan_route,
    step,
)
from .problem import N3Z_MIN, STATE_NAMES, Problem, State  # noqa: E402
from .result import Certificate, Measures, PlanResult, SolverStats, Trajectory  # noqa: E402
from .robot import Robot, default_robot, load_robot  # noqa: E402
from .version import __version__  # noqa: E402
from .waypoints import read_waypoints  # noqa: E402

if _GUARDED and not _interrupts.cli_follows():   # python -m rollplan.<another module>: guard no longer
    _interrupts.end_start_up()

__all__ = [
    "__version__",
    "A_MAX", "Curve", "Piece", "circle_point", "figure_eight",
    "InputError", "NoPlanError", "SolverError",
    "STATE_NAMES", "N3Z_MIN", "State", "Problem",
    "Certificate", "Measures", "PlanResult", "SolverStats", "Trajectory",
    "METHODS", "solve",
    "SOLVERS", "GeometricPhasePlanner", "Plan", "StepResult", "plan", "step",
    "LEGS", "ComposedPlanner", "ComposedPlan", "as_composed", "Route", "plan_route", "read_waypoints",
    "CollocationPlanner", "CollocationResult", "collocate",
    "Robot", "load_robot", "default_robot",
    "Motion", "actuate", "Simulation", "simulate_rotors",
]
