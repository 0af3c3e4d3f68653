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
    assert np.trapezoid(line.get_ydata(), m.series.time) == pytest.approx(p.path_length, rel=1e-3)


WAYPOINTS = "u_a,v_a,psi,u_o,v_o,steps,label\n0,0,0,,,,home\n1.0,0.5,0.3,,,1,a\n1.0,0.5,1.3,,,1,turn in place\n" \
            "1.2,0.4,1.5,0.3,-0.2,2,inspect\n0,0,0,0,0,1,home again\n"


def test_route_figure_marks_and_labels_every_waypoint(tmp_path):
    """route.png neither marked nor labelled the waypoints: each point of the CSV file is marked, and labelled
    with the numbers and labels of the waypoints there."""
    from rollplan.plots.composed import plot_composed

    (tmp_path / "w.csv").write_text(WAYPOINTS)
    r = rollplan.plan_route(rollplan.read_waypoints(tmp_path / "w.csv"), k=2.5)
    ax = plot_composed(r, r.sample(400)).axes[0]
    marks = [ln for ln in ax.get_lines() if ln.get_label() == "_waypoint"]
    points = sorted((float(ln.get_xdata()[0]), float(ln.get_ydata()[0])) for ln in marks)
    assert np.allclose(points, [(0.0, 0.0), (1.0, 0.5), (1.2, 0.4)], rtol=0, atol=1e-12)   # the file's points
    texts = sorted(t.get_text() for t in ax.texts)
    assert texts == ["1 home, 5 home again", "2 a, 3 turn in place", "4 inspect"]
    for ln in marks:
        assert ln.get_zorder() > max(other.get_zorder() for other in ax.get_lines() if other.get_label() != "_waypoint")


def test_simulation_figure_draws_the_planned_curve_over_the_simulated_one():
    """In sim.png the planned curve (dashed) was drawn first and hidden under the simulated one."""
    from rollplan.plots.colors import PLANNED, SIMULATED
    from rollplan.plots.motion import plot_simulation
    from rollplan.timeseries import TimeSeries

    t = np.linspace(0.0, 1.0, 50)
    states = np.column_stack([t, t ** 2, t, 0 * t, 0 * t])
    fig = plot_simulation(TimeSeries(t, states, rotor_rates=np.zeros((50, 2))), states[-1], planned=states)
    for ax in fig.axes[:2]:
        planned = [ln for ln in ax.get_lines() if ln.get_color() == PLANNED and ln.get_linestyle() == "--"]
        simulated = [ln for ln in ax.get_lines() if ln.get_color() == SIMULATED and len(ln.get_xdata()) == 50]
        assert planned and simulated
        assert min(ln.get_zorder() for ln in planned) > max(ln.get_zorder() for ln in simulated)


@pytest.fixture(scope="module")
def rolled():
    """The default robot, its plan to (0, 0.1, 1) and the rotor-driven simulation of its 10 s motion."""
    robot = rollplan.default_robot()
    p = rollplan.plan((0.0, 0.1, 1.0), robot=robot)
    m = actuate(p, robot, 10.0)
    return robot, p, rollplan.simulate_rotors(robot, m.series.time, m.series.rotor_rates, p.goal)


@pytest.mark.slow
def test_the_animation_of_100_frames_stays_under_1_5_mb(tmp_path, rolled):
    """`rollplan animate` wrote 5 MB for 100 frames: one palette and transparent unchanged pixels keep it under
    1.5 MB; the decoded frames show the motion (the first and the middle frame differ in both panels)."""
    from PIL import Image

    from rollplan.plots.animation import make_animation

    robot, p, sim = rolled
    gif = tmp_path / "roll.gif"
    make_animation(sim.series, robot, p.goal, gif, 100, 20)
    assert gif.stat().st_size < 1.5e6
    im = Image.open(gif)
    assert im.n_frames == 100
    first = np.asarray(im.convert("RGB"), int)
    im.seek(50)
    middle = np.asarray(im.convert("RGB"), int)
    half = first.shape[1] // 2
    assert np.any(first[:, :half] != middle[:, :half]) and np.any(first[:, half:] != middle[:, half:])
    assert np.all(first[:5] == 255) == np.all(middle[:5] == 255)   # the static parts are unchanged


@pytest.mark.slow
def test_the_animation_draws_only_what_moves_and_shows_the_same_frames(tmp_path, rolled):
    """Each frame is the figure's still parts drawn once with the moving artists drawn over them: the frames are
    those of matplotlib drawing every frame whole (but for a few pixels where the cursor crosses an axis line)."""
    from PIL import Image

    from rollplan.plots.animation import make_animation

    robot, p, sim = rolled
    frames = {}
    for blit in (True, False):
        make_animation(sim.series, robot, p.goal, tmp_path / f"{blit}.gif", 6, 20, dpi=60, blit=blit)
        im = Image.open(tmp_path / f"{blit}.gif")
        frames[blit] = []
        for i in range(im.n_frames):
            im.seek(i)
            frames[blit].append(np.asarray(im.convert("RGB"), int))
    assert len(frames[True]) == len(frames[False]) == 6
    assert np.any(frames[True][0] != frames[True][3])   # it moves
    for fast, whole in zip(frames[True], frames[False]):
        assert np.count_nonzero(np.any(fast != whole, axis=2)) <= 8


@pytest.mark.slow
def test_the_legends_drawn_once_give_the_same_gif(tmp_path, monkeypatch, rolled):
    """The legends (slow text) are drawn once and kept in the frames no moving artist drawn before them meets:
    the GIF is byte for byte the one with the legends drawn again on every frame, and some frames keep them."""
    from rollplan.plots import animation

    robot, p, sim = rolled
    met = []
    overlaps = animation.overlaps
    monkeypatch.setattr(animation, "overlaps", lambda *a: met.append(overlaps(*a)) or met[-1])
    animation.make_animation(sim.series, robot, p.goal, tmp_path / "kept.gif", 12, 20, dpi=50)
    assert True in met and False in met   # the cursor passes under the legend of the rotor rates, not always
    monkeypatch.setattr(animation, "overlaps", lambda *a: True)
    animation.make_animation(sim.series, robot, p.goal, tmp_path / "redrawn.gif", 12, 20, dpi=50)
    assert (tmp_path / "kept.gif").read_bytes() == (tmp_path / "redrawn.gif").read_bytes()


def test_spikes_are_clipped_to_a_robust_range_and_marked():
    """End spikes of +-1000 flattened the compare torque panels: the y-range keeps the bulk of the samples
    (amplitude 100 here), the spikes are marked by triangles on the edge and their values are written."""
    from matplotlib.figure import Figure

    from rollplan.plots.common import SPIKE_LABEL, clip_spikes

    t = np.linspace(0.0, 1.0, 501)
    v = np.column_stack([100 * np.sin(2 * np.pi * t), 80 * np.cos(2 * np.pi * t)])
    v[0], v[-1] = (1000.0, -900.0), (-1000.0, 950.0)
    ax = Figure().subplots()
    ax.plot(t, v)
    assert clip_spikes(ax, t, v, ("C0", "C1"))
    low, high = ax.get_ylim()
    assert -1000 < low < -100 and 100 < high < 950
    marks = [ln for ln in ax.get_lines() if ln.get_label() == SPIKE_LABEL]
    assert sorted(float(x) for ln in marks for x in ln.get_xdata()) == [0.0, 0.0, 1.0, 1.0]
    assert any("-1000" in txt.get_text() and "1000" in txt.get_text() for txt in ax.texts)
    calm = Figure().subplots()   # nothing far out: the range is matplotlib's own
    assert not clip_spikes(calm, t, v[1:-1], ("C0", "C1"))


@pytest.mark.slow
def test_compare_torque_panels_exclude_the_end_spikes():
    """The default compare (N = 100): torques of about +-150 with end spikes of +-1087 (geometric phase) and
    -816 (collocation), the discrete form of the impulsive start and stop of the |omega|^2 optimum."""
    from rollplan.plots.compare import plot_comparison
    from rollplan.studies import comparison

    c = comparison.compare((0.5, 0.3, 0.4), 1, 2.5, None, None, 1.0, "angular_velocity", 100, 3, "legendre",
                           comparison.CONTACT_BOUND, 1)
    fig = plot_comparison(c)
    for side in (c.gp, c.collocation):
        tau = side.motion.rotor_torques
        (ax,) = [a for a in fig.axes if a.get_title().endswith("motor torques") and
                 np.allclose(a.get_lines()[0].get_ydata(), tau[:, 0])]
        low, high = ax.get_ylim()
        assert low > tau.min() or high < tau.max()   # the spikes are outside
        inner = np.quantile(tau, [0.05, 0.95])
        assert low < inner[0] and inner[1] < high     # the bulk inside


@pytest.fixture(scope="module")
def atlases():
    """Two atlases of the paper's k (about 2 s: the tests that use them are in the full tier)."""
    from rollplan.studies.atlas import compute_atlas

    return compute_atlas(2.5, 1, 21), compute_atlas(2.5, 1, 41)


@pytest.mark.slow
def test_atlas_reachable_panel_has_no_sampling_holes(atlases):
    """The reachability histogram's white holes were gaps between grid points that read as unreachable
    regions: the images of the grid cells are filled, so the pairs a finer grid reaches (points between the
    coarse grid's) lie in the filled region, also where the coarse histogram has no point."""
    from matplotlib.collections import PolyCollection

    from rollplan.core.plane import wrap
    from rollplan.plots.atlas import plot_atlas

    coarse, fine = atlases
    (ax,) = [a for a in plot_atlas(coarse).axes if a.get_xlabel().startswith("turn")]
    paths = [p for c in ax.collections if isinstance(c, PolyCollection) for p in c.get_paths()]
    assert paths
    pts = np.column_stack([wrap(fine.turn_total.ravel()), fine.shift_total.ravel()])
    inside = np.zeros(len(pts), bool)
    for p in paths:
        inside |= p.contains_points(pts)
    hist, xe, ye = np.histogram2d(wrap(coarse.turn_total.ravel()), coarse.shift_total.ravel(), bins=(72, 60),
                                  range=((-np.pi, np.pi), (0.0, float(coarse.shift_total.max()))))
    ix = np.clip(np.searchsorted(xe, pts[:, 0]) - 1, 0, 71)
    iy = np.clip(np.searchsorted(ye, pts[:, 1]) - 1, 0, 59)
    in_a_hole = (hist[ix, iy] == 0) & (pts[:, 1] < ye[-1])
    assert in_a_hole.sum() > 100                        # the coarse grid's histogram alone has holes there
    # the quadrilaterals approximate the curved image of each cell: a few points near the folds fall just outside
    assert inside[in_a_hole].mean() > 0.9 and inside.mean() > 0.9


@pytest.mark.slow
def test_atlas_contours_leave_the_crowded_corner_to_the_colours(atlases):
    """An atlas corner (a, b near A_MAX) was a tangle of white contours: none is drawn where a or b exceeds
    the labelled region."""
    from rollplan.plots.atlas import plot_atlas

    coarse, _ = atlases
    fig = plot_atlas(coarse)
    limit = float(fig.axes[0].get_legend().get_texts()[1].get_text().split("< ")[1].split(" R")[0])
    step = float(coarse.a[1] - coarse.a[0])
    for ax in fig.axes[:2]:   # h and eta: the contour lines (not filled, not the fold's single level 0)
        white = [c for c in ax.collections if hasattr(c, "allsegs") and not c.filled and list(c.levels) != [0.0]]
        assert len(white) == 1
        for cs in white:
            for segs in cs.allsegs:
                for seg in segs:
                    assert len(seg) == 0 or np.max(seg) <= limit + step   # b, a of every point of the line


def test_curve_families_figure_draws_what_the_report_holds():
    """Every family's value of every row is a marker of the family's colour at that value, filled exactly where the
    report says a non-stop timing with continuous torques exists; a family without a plan draws nothing."""
    from rollplan.plots.colors import FAMILY
    from rollplan.plots.curve_families import plot_curve_families

    def fam(x, nonstop):
        return {"path_length": x, "omega2": 10 * x, "t_min": x / 2, "nonstop_continuous": nonstop}

    report = {"rows": [{"target": [0, 1, 0], "steps": 1, "k": 2.5,
                        "families": {"circles": fam(3.0, False), "viviani": fam(2.5, True), "triangle": fam(4.0, False),
                                     "square": {"error": "no plan"}}},
                       {"target": [0.5, 0.3, 0.4], "steps": 2, "k": 10.0,
                        "families": {"circles": fam(5.0, False), "viviani": fam(6.0, False),
                                     "triangle": fam(7.0, False), "square": fam(8.0, False)}}]}
    fig = plot_curve_families(report)
    for ax, key in zip(fig.axes, ("path_length", "omega2", "t_min")):
        drawn = {(ln.get_color(), round(float(ln.get_ydata()[0]), 9), ln.get_markerfacecolor() != "white")
                 for ln in ax.get_lines()}
        expect = {(FAMILY[n], round(f[key], 9), f["nonstop_continuous"]) for r in report["rows"]
                  for n, f in r["families"].items() if "error" not in f}
        assert drawn == expect
    assert "k=10" in fig.axes[-1].get_xticklabels()[1].get_text()


def _laid_out_figure():
    """A figure with a layout engine and what it lays out: two panels, a colour bar, a legend, a title."""
    from matplotlib.figure import Figure

    fig = Figure(figsize=(3, 1.5), layout="constrained")
    left, right = fig.subplots(1, 2)
    t = np.linspace(0.0, 1.0, 50)
    left.plot(t, np.sin(6 * t), label="a long legend entry")
    left.legend(loc="upper right")
    left.set_ylabel("a label far to the left [rad/s]")
    image = right.imshow(np.outer(t, t), aspect="auto")
    fig.colorbar(image, ax=right, label="colour bar")
    fig.suptitle("laid out")
    return fig


def test_a_laid_out_figure_is_drawn_once_and_saved_as_matplotlib_saves_it(tmp_path, monkeypatch):
    """save_figure lays a constrained figure out without matplotlib's extra draw: the same bytes as
    ``savefig`` (the layout that draw ran is the same), one draw instead of two; with ``savefig.bbox`` tight
    (which measures a drawn figure) matplotlib's own two draws."""
    import io

    import matplotlib
    from matplotlib.figure import Figure

    from rollplan.outputs import save_figure

    draws = []
    draw = Figure.draw
    monkeypatch.setattr(Figure, "draw", lambda self, renderer: draws.append(1) or draw(self, renderer))
    fig = _laid_out_figure()
    save_figure(fig, tmp_path / "fig.png")
    assert len(draws) == 1 and "draw" not in fig.__dict__
    expected = io.BytesIO()
    _laid_out_figure().savefig(expected, format="png", dpi=120)
    assert len(draws) == 3
    assert (tmp_path / "fig.png").read_bytes() == expected.getvalue()
    with matplotlib.rc_context({"savefig.bbox": "tight"}):
        save_figure(_laid_out_figure(), tmp_path / "tight.png")
    assert len(draws) == 5
