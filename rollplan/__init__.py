"""rollplan: exact, dynamically realizable motion planning for a spherical robot
driven by two internal rotors (Svinin, Morinaga, Yamamoto)."""

from .collocation import CollocationPlanner, CollocationResult, collocate
from .curves import A_MAX, Curve, Piece, circle_point, figure_eight
from .errors import InputError, NoPlanError, SolverError
from .geometric import SOLVERS, GeometricPhasePlanner, Plan, SolverStats, StepResult, Trajectory, plan, step
from .robot import Robot, load_robot
from .actuation import Motion, actuate
from .robot import default_robot
from .simulate import Simulation, simulate_rotors

__version__ = "0.1.0"

__all__ = [
    "A_MAX", "Curve", "Piece", "circle_point", "figure_eight",
    "InputError", "NoPlanError", "SolverError",
    "SOLVERS", "GeometricPhasePlanner", "Plan", "SolverStats", "StepResult", "Trajectory", "plan", "step",
    "Robot", "load_robot",
    "Motion", "actuate", "default_robot", "Simulation", "simulate_rotors",
    "CollocationPlanner", "CollocationResult", "collocate",
]
