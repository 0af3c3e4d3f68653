"""The geometric-phase planner: figure eights traced n times (Section III.B of the paper), and its
extension to any start and goal state.

Pieces: :mod:`.leafmap` (the accurate leaf map: closed-form turn, Gauss-rule displacement, up to K_MAX),
:mod:`.compiled_search` (the C planner's search: complete enumeration of the roots of (32)-(33) for every k;
constants in :mod:`.search_constants`), :mod:`.refine` (the polish: root solvers by name),
:mod:`.certify` (independent integration of the whole motion), :mod:`.planner` (the pole-to-pole problem class
:class:`GeometricPhasePlanner`); full reconfiguration: :mod:`.maneuvers` (approach and departure rolls),
:mod:`.turn` (turning in place), :mod:`.legs` (two legs), :mod:`.basepoint` (figure eights off the pole),
:mod:`.composed` (:class:`ComposedPlanner` and :func:`plan`, for any start and goal), :mod:`.route`, :mod:`.many`
(:func:`plan_many`: many targets per call). Design: docs/design/geometric-planner.md.
"""

from .composed import BASES, LEGS, POLISHES, ComposedPlan, ComposedPlanner, as_composed, plan
from .many import PlanMany, plan_many
from .planner import CURVE_CHOICES, TOLERANCE, GeometricPhasePlanner, Plan, StepResult, default_planner, step
from .refine import DEFAULT_ROOT_SOLVER, SOLVERS
from .route import Route, plan_route

__all__ = ["TOLERANCE", "CURVE_CHOICES", "SOLVERS", "DEFAULT_ROOT_SOLVER", "LEGS", "BASES", "POLISHES",
           "GeometricPhasePlanner", "Plan", "StepResult", "default_planner", "plan", "step", "ComposedPlanner",
           "ComposedPlan", "as_composed", "Route", "plan_route", "PlanMany", "plan_many"]
