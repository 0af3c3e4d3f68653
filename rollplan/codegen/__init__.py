"""C code generation: a self-contained C99 planner for the robot's microcontroller (:mod:`.c_library`)."""

from .c_library import AUTO_STEPS_PER_LEAF, DEFAULT_PREFIX, DEFAULT_STEPS_PER_LEAF, GeneratedCode, generate

__all__ = ["AUTO_STEPS_PER_LEAF", "DEFAULT_PREFIX", "DEFAULT_STEPS_PER_LEAF", "GeneratedCode", "generate"]
