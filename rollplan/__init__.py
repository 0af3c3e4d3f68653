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

# Names are imported on first use (PEP 562), so that `import rollplan` and the `rollplan` command load only
# what they use (the collocation planner, the execution layer and the plots are not needed for a plan).
_LAZY = {
    "A_MAX": "core.curves", "Curve": "core.curves", "Piece": "core.curves", "circle_point": "core.curves",
    "figure_eight": "core.curves",
    "InputError": "errors", "NoPlanError": "errors", "SolverError": "errors", "UnsafeCacheError": "errors",
    "Actuation": "execution.actuation", "actuate": "execution.actuation",
    "RotorSimulation": "execution.plants", "simulate_rotors": "execution.plants",
    "METHODS": "planners", "Method": "planners", "solve": "planners",
    "CollocationPlanner": "planners.collocation", "CollocationResult": "planners.collocation",
    "collocate": "planners.collocation",
    **dict.fromkeys(("LEGS", "SOLVERS", "ComposedPlan", "ComposedPlanner", "GeometricPhasePlanner", "Plan", "Route",
                     "StepResult", "as_composed", "plan", "plan_route", "step", "PlanMany", "plan_many"),
                    "planners.geometric"),
    "N3Z_MIN": "problem", "STATE_NAMES": "problem", "Problem": "problem", "State": "problem",
    "CERTIFICATE_TOLERANCE": "result", "Certificate": "result", "Measures": "result", "PlanResult": "result",
    "SolverStats": "result", "Trajectory": "result",
    "Robot": "robot", "default_robot": "robot", "load_robot": "robot",
    "TimeSeries": "timeseries",
    "read_waypoints": "waypoints",
}

from .version import __version__  # noqa: E402


def __getattr__(name: str):
    if name in _LAZY:
        import importlib

        value = getattr(importlib.import_module(f".{_LAZY[name]}", __name__), name)
        globals()[name] = value
        return value
    raise AttributeError(f"module 'rollplan' has no attribute {name!r}")


def __dir__():
    return sorted(set(globals()) | set(_LAZY))


if _GUARDED and not _interrupts.cli_follows():   # python -m rollplan.<another module>: guard no longer
    _interrupts.end_start_up()

__all__ = [
    "__version__",
    "A_MAX", "Curve", "Piece", "circle_point", "figure_eight",
    "InputError", "NoPlanError", "SolverError", "UnsafeCacheError",
    "STATE_NAMES", "N3Z_MIN", "State", "Problem",
    "CERTIFICATE_TOLERANCE", "Certificate", "Measures", "PlanResult", "SolverStats", "Trajectory", "TimeSeries",
    "METHODS", "Method", "solve",
    "SOLVERS", "GeometricPhasePlanner", "Plan", "StepResult", "plan", "step", "PlanMany", "plan_many",
    "LEGS", "ComposedPlanner", "ComposedPlan", "as_composed", "Route", "plan_route", "read_waypoints",
    "CollocationPlanner", "CollocationResult", "collocate",
    "Robot", "load_robot", "default_robot",
    "Actuation", "actuate", "RotorSimulation", "simulate_rotors",
]
