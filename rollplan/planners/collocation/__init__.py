"""The direct-collocation optimal-control planner: :mod:`.transcription` (grid and equations),
:mod:`.costs` (running costs by name), :mod:`.planner` (the NLP, its solve and certification)."""

from .costs import COSTS, Cost
from .planner import (
                      CONTACT_BOUND,
                      GUESSES,
                      SMOOTHING,
                      TOLERANCE,
                      CollocationPlanner,
                      CollocationResult,
                      CollocationSolution,
                      collocate,
)
from .transcription import SCHEMES, Guess, Transcription

__all__ = ["COSTS", "Cost", "CONTACT_BOUND", "GUESSES", "SMOOTHING", "TOLERANCE", "CollocationPlanner",
           "CollocationResult", "CollocationSolution", "collocate", "SCHEMES", "Guess", "Transcription"]
