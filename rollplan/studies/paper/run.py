"""Reproduction of the paper's case study (Section III.C): every number, every figure, the report.

:func:`run_case_study` runs the stages of :mod:`.stages` (computation), turns
their evidence into rows with :func:`.report.case_study_rows` (prose), and
:func:`reproduce` writes Figs 6-12 (:mod:`rollplan.plots.paper`),
``reproduction.json`` and ``REPRODUCTION.md`` (:func:`.report.markdown`).
A paper number counts as *reproduced* when the computed value, rounded to the
digits the paper prints, equals the printed value; otherwise it is a
*discrepancy*, and the evidence is recorded in the row's note.
"""

from __future__ import annotations

import logging
import time
from dataclasses import dataclass, field
from pathlib import Path

from ...errors import InputError, check_whole
from ...io import tagged
from ...outputs import check_writable, make_folder, save_figure, write_atomic, write_json
from ...plots.paper import case_study_figures
from .report import case_study_rows, markdown
from .stages import (
    CaseStudy,
    Progress,
    Sweep,
    crossings_stage,
    pure_rolling_stage,
    radius_stage,
    shift_stage,
    trajectories_stage,
    zeros_stage,
)
from .values import FIGURES, PAPER

__all__ = ["CaseStudyResult", "run_case_study", "write_reproduction", "reproduce"]

log = logging.getLogger(__name__)


@dataclass(frozen=True)
class CaseStudyResult:
    """Everything the case study computes; plots and reports take it and compute nothing.

    Attributes
    ----------
    rows : tuple of Row
        One row per number or claim of Section III.C.
    a0 : float
        Radius [R] with h/R = 1 at k = 0 (spectral root).
    a0_printed : float
        The paper's printed radius 0.533681 [R].
    k_sweep, k_sweep_printed : Sweep
        h(k) for a0 and for the printed radius (Fig. 9).
    a_sweep : Sweep
        h(a) for k = 2.5 (Fig. 10); ``roots`` are the a_i with h/R = 1.
    plans : dict of str -> (Plan, Trajectory)
        The sampled trajectories of Figs 6-8 (``"k0"``, ``"k2.5"``, ``"k5"``)
        and 11-12 (``"a1"``, ``"a2"``), each verified by CVODES.
    crossings : tuple of Crossings
        The self-intersection table.
    evidence : dict
        Named numbers behind the discrepancy notes (both integrators, closed form).
    timings : dict of str -> float
        Wall time of each stage [s].
    """

    rows: tuple
    a0: float
    a0_printed: float
    k_sweep: Sweep
    k_sweep_printed: Sweep
    a_sweep: Sweep
    plans: dict
    crossings: tuple
    evidence: dict
    timings: dict = field(default_factory=dict)


_STAGES = ("build", "k = 0 radius", "Fig. 9 sweeps", "Fig. 10 sweep", "self-intersections", "trajectories")


def run_case_study(k_points: int = 701, a_points: int = 1400, samples: int = 400,
                   crossing_samples: int = 1000, crossings_per_interval: int = 3,
                   progress: Progress | None = None, study: CaseStudy | None = None) -> CaseStudyResult:
    """Compute every number and claim of Section III.C (no files written).

    Parameters
    ----------
    k_points : int
        Points of the k sweep on ``K_RANGE`` (Fig. 9), >= 20.
    a_points : int
        Points of the a sweep on ``[A_MIN, A_MAX]`` for k = 2.5 (Fig. 10), >= 50.
    samples : int
        CVODES samples per half-step of the figure trajectories, >= 20.
    crossing_samples : int
        Samples of the half-step path for counting self-intersections (the
        count is repeated with 2 and 4 times as many), >= 50.
    crossings_per_interval : int
        Values of k tested in each interval ``[k_i, k_{i+1}]``, >= 1.
    progress : callable, optional
        ``progress(label, done, total)``, called as the work advances.
    study : CaseStudy, optional
        Reuse a built step map.

    Returns
    -------
    CaseStudyResult
    """
    for name, value, low in (("k_points", k_points, 20), ("a_points", a_points, 50), ("samples", samples, 20),
                             ("crossing_samples", crossing_samples, 50),
                             ("crossings_per_interval", crossings_per_interval, 1)):
        check_whole(name, value, low, 10**6)
    timings: dict = {}
    clock = [time.perf_counter()]

    def done(i: int) -> None:
        now = time.perf_counter()
        timings[_STAGES[i]] = now - clock[0]
        clock[0] = now
        log.info("stage %s done in %.2f s", _STAGES[i], timings[_STAGES[i]])
        if progress is not None:
            progress("reproduce", i + 1, len(_STAGES))

    study = study or CaseStudy()
    done(0)
    ev = pure_rolling_stage(study)
    done(1)
    ev.update(shift_stage(study, ev["a0"], ev["a0_printed"]))
    (k_sweep, k_sweep_p), zev = zeros_stage(study, ev["a0"], ev["a0_printed"], k_points, progress)
    ev.update(zev)
    done(2)
    a_sweep, aev = radius_stage(study, a_points, progress)
    ev.update(aev)
    done(3)
    crossings = crossings_stage(study, ev["a0"], k_sweep.roots, crossing_samples, crossings_per_interval, progress)
    done(4)
    plans, tev = trajectories_stage(study, ev["a0"], a_sweep.roots, samples, progress)
    ev.update(tev)
    done(5)
    rows = case_study_rows(ev, k_sweep, a_sweep, crossings, plans)
    return CaseStudyResult(rows, ev["a0"], ev["a0_printed"], k_sweep, k_sweep_p, a_sweep, plans, crossings, ev,
                           timings)


def write_reproduction(result: CaseStudyResult, out, figures: bool = True) -> list:
    """Write fig06.png ... fig12.png, reproduction.json and REPRODUCTION.md into the folder ``out``.

    Returns the list of written paths. Files are written atomically.
    """
    out = Path(out)
    if not out.is_dir():
        raise InputError(f"output folder {str(out)!r} does not exist")
    check_writable(out / "reproduction.json")
    written = []
    if figures:
        for name, fig in zip(FIGURES, case_study_figures(result, PAPER)):
            save_figure(fig, out / name)
            written.append(out / name)
    write_json(out / "reproduction.json", tagged({"rows": [r.as_dict() for r in result.rows]}, "R"))
    written.append(out / "reproduction.json")
    write_atomic(out / "REPRODUCTION.md", markdown(result, FIGURES if figures else ()).encode())
    written.append(out / "REPRODUCTION.md")
    return written


def reproduce(out, progress: Progress | None = None, **options) -> CaseStudyResult:
    """Reproduce Section III.C into the folder ``out`` (created if missing); see :func:`run_case_study`."""
    out = make_folder(out, parents=True)
    for name in (*FIGURES, "reproduction.json", "REPRODUCTION.md"):
        check_writable(out / name)  # fail now, not after the computation
    result = run_case_study(progress=progress, **options)
    t0 = time.perf_counter()
    write_reproduction(result, out)
    result.timings["figures and report"] = time.perf_counter() - t0
    # the report states the timings; rewrite it with the final stage included
    write_atomic(out / "REPRODUCTION.md", markdown(result, FIGURES).encode())
    return result
