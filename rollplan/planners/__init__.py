"""Planning methods for one :class:`~rollplan.problem.Problem`, by name, and :func:`solve`.

Every method is a :class:`~.method.Method`: built with keyword options only (all defaulted), its
``solve(problem)`` checks the problem, solves, requires the certificate and returns a result satisfying
:class:`rollplan.result.PlanResult` (or raises :class:`~rollplan.errors.InputError` (bad input),
:class:`~rollplan.errors.NoPlanError` (no certified plan) or :class:`~rollplan.errors.SolverError` (a solver
broke down)). :data:`METHODS` maps the names to the classes:

``"geometric"``
    Figure eights traced n times, Section III.B (:mod:`.geometric`): exact plans between any two states
    (:class:`.geometric.ComposedPlanner`).
``"collocation"``
    Direct collocation of the optimal-control problem on the same model, contact rates as controls, on a
    fixed horizon (:class:`.collocation.CollocationPlanner`).
``"rest_to_rest"``
    Direct collocation with the contact accelerations as controls, at rest at both ends
    (:class:`.collocation.rest.RestToRestMethod`).
``"minimum_time"``
    The rest-to-rest problem in least time within the robot's rotor limits
    (:class:`.collocation.rest.MinimumTimeMethod`).
"""

from __future__ import annotations

import importlib
import inspect
from collections.abc import Mapping

from ..errors import InputError, show
from ..problem import Problem
from .method import Method

__all__ = ["METHODS", "Method", "method_class", "solve"]


class _Methods(Mapping):
    """Method classes by name, each imported on first access (a plan by one method does not load the others)."""

    _where = {"geometric": (".geometric", "ComposedPlanner"),
              "collocation": (".collocation", "CollocationPlanner"),
              "rest_to_rest": (".collocation.rest", "RestToRestMethod"),
              "minimum_time": (".collocation.rest", "MinimumTimeMethod")}

    def __getitem__(self, name: str):
        module, cls = self._where[name]
        return getattr(importlib.import_module(module, __name__), cls)

    def __iter__(self):
        return iter(self._where)

    def __len__(self) -> int:
        return len(self._where)


#: Method classes by name (see the module docstring).
METHODS = _Methods()


def method_class(method) -> type[Method]:
    """The :class:`Method` subclass named ``method`` in :data:`METHODS`, or ``method`` itself if it is one;
    InputError naming the choices otherwise."""
    if isinstance(method, type) and issubclass(method, Method):
        return method
    if not isinstance(method, str) or method not in METHODS:
        raise InputError(f"method = {show(method)} is not allowed: choose one of {', '.join(METHODS)} "
                         "or give a rollplan.planners.Method subclass")
    return METHODS[method]


def solve(problem: Problem, method="geometric", **options):
    """Solve ``problem`` by ``method`` (a name in :data:`METHODS`, a :class:`Method` subclass, or an instance
    of one, then without ``options``); ``options`` are the method's constructor keywords."""
    if isinstance(method, Method):
        if options:
            raise InputError(f"options {', '.join(sorted(options))} are not allowed with a method instance: "
                             "give them to its constructor")
        return method.solve(problem)
    cls = method_class(method)
    try:
        inspect.signature(cls).bind(**options)
    except TypeError:
        allowed = [n for n, p in inspect.signature(cls).parameters.items()
                   if p.kind in (p.POSITIONAL_OR_KEYWORD, p.KEYWORD_ONLY) and n != "method"]
        bad = sorted(set(options) - set(allowed))
        raise InputError(f"option {bad[0] if bad else sorted(options)[0]!r} is not allowed for the method "
                         f"{cls.name or cls.__name__!r}: choose among {', '.join(allowed)}") from None
    return cls(**options).solve(problem)
