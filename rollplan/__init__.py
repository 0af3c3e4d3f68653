"""rollplan: exact, dynamically realizable motion planning for a spherical robot driven by two
internal rotors.

It implements, on one symbolic CasADi model, the geometric-phase planner of

    M. Svinin, A. Morinaga and M. Yamamoto, "On the Geometric Phase Approach to Motion Planning for a
    Spherical Rolling Robot in Dynamic Formulation"

(cited in full once, here; everywhere else "the paper" and its equation numbers), and a
direct-collocation optimal-control planner for the same :class:`Problem`.
"""

from .core.curves import A_MAX, Curve, Piece, circle_point, figure_eight
from .errors import InputError, NoPlanError, SolverError
from .execution.actuation import Motion, actuate
from .execution.plants import Simulation, simulate_rotors
from .planners import METHODS, solve
from .planners.collocation import CollocationPlanner, CollocationResult, collocate
from .planners.geometric import (
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
from .problem import N3Z_MIN, STATE_NAMES, Problem, State
from .result import Certificate, Measures, PlanResult, SolverStats, Trajectory
from .robot import Robot, default_robot, load_robot
from .version import __version__
from .waypoints import read_waypoints

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
