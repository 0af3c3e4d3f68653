"""What the figures show (issue 29, items 14 and 17), checked through the matplotlib objects: the unit of
every length axis, waypoints marked and labelled, robust ranges with clipped spikes marked, the planned
curve drawn over the simulated one, and the size of the animation."""

import numpy as np
import pytest

import rollplan
from rollplan.execution.actuation import actuate


def test_timing_phase_plane_is_in_metres_for_a_robot():
    """The phase plane (s, s') of `--timing-plot` was labelled and drawn in R for a robot in metres."""
    from rollplan.plots.timing import plot_timing

    robot = rollplan.default_robot()
    p = rollplan.plan((0.0, 0.1, 0.0), robot=robot)
    m = actuate(p, robot, 10.0)
    phase = plot_timing(m).axes[-1]
    assert "[m]" in phase.get_xlabel() and "[m/s]" in phase.get_ylabel()
    line = next(ln for ln in phase.get_lines() if ln.get_label() == "min-jerk")
    # the contact path's length in metres, as the plan states it, and the mean speed of the whole motion
    assert np.max(line.get_xdata()) == pytest.approx(p.path_length, rel=1e-6)
    assert np.trapezoid(line.get_ydata(), m.time) == pytest.approx(p.path_length, rel=1e-3)
