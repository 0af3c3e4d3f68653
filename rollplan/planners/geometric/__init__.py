"""The geometric-phase planner: figure eights traced n times (Section III.B of the paper).

Pieces: :mod:`.leaves` (tables of the two leaves per k), :mod:`.brackets`
(cells bracketing roots of (32)-(33)), :mod:`.refine` (root solvers by name),
:mod:`.certify` (independent integration of the whole motion), :mod:`.planner`
(the problem class and the functions :func:`plan` and :func:`step`).
"""

from .planner import TOLERANCE, GeometricPhasePlanner, Plan, StepResult, default_planner, plan, step
from .refine import SOLVERS

__all__ = ["TOLERANCE", "SOLVERS", "GeometricPhasePlanner", "Plan", "StepResult", "default_planner", "plan", "step"]
