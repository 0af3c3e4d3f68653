"""The paper's case study (Section III.C) reproduced: :mod:`.values` (the printed numbers),
:mod:`.stages` (the computation), :mod:`.report` (rows and REPRODUCTION.md), :mod:`.run`
(orchestration and files); the figures are in :mod:`rollplan.plots.paper`."""

from .run import CaseStudyResult, reproduce, run_case_study, write_reproduction

__all__ = ["CaseStudyResult", "reproduce", "run_case_study", "write_reproduction"]
