"""Planners: two methods for one :class:`~rollplan.problem.Problem`.

:data:`METHODS` maps a method's name to its planner class. The contract of a
method: the class is built with keyword options only (all defaulted), and its
``solve(problem)`` returns a result satisfying
:class:`rollplan.result.PlanResult` whose certificate has passed, or raises
:class:`~rollplan.errors.InputError` (bad input),
:class:`~rollplan.errors.NoPlanError` (no plan) or
:class:`~rollplan.errors.SolverError` (the solver broke down).

``"geometric"``
    Figure eights traced n times, Section III.B (:mod:`.geometric`): exact
    plans from rest at the origin to a goal at the pole, and, composed with
    approach and departure rolls, turns in place and two legs, between any two
    states (:class:`.geometric.ComposedPlanner`).
``"collocation"``
    Direct collocation of the optimal-control problem on the same model (:mod:`.collocation`).
"""

from __future__ import annotations

from ..errors import InputError
from ..problem import Problem
from .collocation import CollocationPlanner
from .geometric import ComposedPlanner

__all__ = ["METHODS", "solve"]

#: Planner classes by method name (see the module docstring for the contract).
METHODS = {"geometric": ComposedPlanner, "collocation": CollocationPlanner}


def solve(problem: Problem, method: str = "geometric", **options):
    """Solve ``problem`` by the method named ``method``; ``options`` go to its planner class."""
    if not isinstance(method, str) or method not in METHODS:
        raise InputError(f"method = {method!r} is not allowed: choose one of {', '.join(METHODS)}")
    return METHODS[method](**options).solve(problem)
