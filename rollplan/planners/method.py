"""The base class of every planning method: options in the constructor, one ``solve(problem)``.

A method is built with keyword options only (all defaulted; root solver, steps, legs, intervals, cost...
live here, not in :class:`~rollplan.problem.Problem`), and its :meth:`Method.solve` runs the same four
stages for every method: check the problem, :meth:`Method._solve`, require the certificate
(:func:`rollplan.result.require_certified`), return the result (a :class:`rollplan.result.PlanResult`).
The registry of methods by name is :data:`rollplan.planners.METHODS`. Contract: docs/planning.md.
"""

from __future__ import annotations

import copy
import warnings
from typing import ClassVar

from ..errors import InputError
from ..problem import Problem
from ..result import PlanResult, require_certified

__all__ = ["Method", "renamed_option", "with_steps"]


class Method:
    """A planning method (subclass it; register it in :data:`rollplan.planners.METHODS`).

    Subclasses set :attr:`name`, take their options as constructor keywords (validated there, with
    one-line InputErrors) and implement :meth:`_solve`; they may extend :meth:`_check`.

    Attributes
    ----------
    name : str
        The method's name in the registry and its results' ``method``.
    """

    name: ClassVar[str] = ""

    def solve(self, problem: Problem) -> PlanResult:
        """Solve ``problem``: check -> :meth:`_solve` -> certificate required -> the result.

        Raises
        ------
        InputError
            Bad input (the problem, or one this method does not serve).
        NoPlanError
            No plan, or none whose certificate passes (never a plan above its tolerance).
        SolverError
            A numerical solver broke down.
        """
        problem = self._check(problem)
        return require_certified(self._solve(problem), problem.describe())

    def _check(self, problem) -> Problem:
        """The problem, if this method can take it; InputError otherwise."""
        if not isinstance(problem, Problem):
            raise InputError(f"problem = {problem!r:.60} is not allowed: give a rollplan.Problem")
        return problem

    def _solve(self, problem: Problem) -> PlanResult:
        raise NotImplementedError

    def _with(self, **options) -> Method:
        """A shallow copy with some per-solve options changed (for the positional per-call arguments that
        :meth:`solve` of some methods still accepts); ``self`` when nothing changes."""
        def same(old, new) -> bool:
            return old is new or (isinstance(new, (bool, int, float, str)) and type(old) is type(new) and old == new)

        if all(same(getattr(self, name), value) for name, value in options.items()):
            return self
        other = copy.copy(self)
        for name, value in options.items():
            setattr(other, name, value)
        return other


def with_steps(problem: Problem, steps: int | None) -> Problem:
    """``problem`` with the method's ``steps`` (figure eights per leg), or as it is when ``steps`` is None."""
    if steps is None or steps == problem.steps:
        return problem
    return Problem(problem.goal, problem.start, None if problem.robot is not None else problem.k, problem.robot,
                   problem.radius, steps)


def renamed_option(old: str, old_value, new: str, new_value, default) -> tuple:
    """``(value, name)`` of an option renamed from ``old`` to ``new``: ``new_value`` (or ``default``) and
    ``new``, or, with a DeprecationWarning, ``old_value`` and ``old`` when only the old name was given
    (InputError when both were). ``name`` is the one to name in a message about the value."""
    if old_value is None:
        return (default if new_value is None else new_value), new
    if new_value is not None:
        raise InputError(f"give {new} only ({old} is its old name)")
    warnings.warn(f"the keyword {old}= is deprecated: use {new}=", DeprecationWarning, stacklevel=3)
    return old_value, old
