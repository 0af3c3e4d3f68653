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

import importlib
from collections.abc import Mapping

from ..errors import check_choice
from ..problem import Problem

__all__ = ["METHODS", "solve"]


class _Methods(Mapping):
    """Planner classes by method name, each imported on first access (a plan by one method does not load
    the other)."""

    _where = {"geometric": (".geometric", "ComposedPlanner"), "collocation": (".collocation", "CollocationPlanner")}

    def __getitem__(self, name: str):
        module, cls = self._where[name]
        return getattr(importlib.import_module(module, __name__), cls)

    def __iter__(self):
        return iter(self._where)

    def __len__(self) -> int:
        return len(self._where)


#: Planner classes by method name (see the module docstring for the contract).
METHODS = _Methods()


def solve(problem: Problem, method: str = "geometric", **options):
    """Solve ``problem`` by the method named ``method``; ``options`` go to its planner class."""
    check_choice("method", method, METHODS)
    return METHODS[method](**options).solve(problem)
